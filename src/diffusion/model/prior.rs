//! The template prior: each occupied cell's primitive sampled with a fixed seed and
//! laid out like x_0.

use super::*;

/// The template priors of a batch of contexts as a [B, 3, 64, 96] tensor (each
/// cell's visible part with `visible`, see [`prior_image_visible`]).
pub(super) fn prior_tensor(ctx: Tensor<2>, device: &Device, visible: bool) -> Tensor<4> {
    let b = ctx.dims()[0];
    let oh: Vec<f32> = ctx.into_data().convert::<f32>().try_into_vec::<f32>().unwrap_or_default();
    let img: Vec<f32> = oh.chunks(CONTEXT_DIM).flat_map(|o| prior_image_of(o, visible)).collect();
    Tensor::<4>::from_data(TensorData::new(img, [b, 3, TENSOR_H, TENSOR_W]), device)
}

/// Seed of the template prior's samples (fixed: the prior is a function of the context).
pub const PRIOR_SEED: u64 = 0x5052_494f_52;

/// The template prior of one 132-vector: [3, 64, 96] laid out like x_0, each occupied
/// cell holding 512 points of its primitive sampled with a fixed seed (scale 1, sorted);
/// null cells and occupied cells whose label is withheld (an all-zero row, see
/// `Context::one_hot_unlabelled`) hold zeros. The occupied box, hence the frame, counts
/// withheld cells as occupied.
pub fn prior_image(one_hot: &[f32]) -> Vec<f32> {
    prior_image_of(one_hot, false)
}

/// [`prior_image`] with each cell's primitive sampled off the faces it shares with
/// occupied neighbours (`dataset::sample_cells_visible`).
pub fn prior_image_visible(one_hot: &[f32]) -> Vec<f32> {
    prior_image_of(one_hot, true)
}

pub(super) fn prior_image_of(one_hot: &[f32], visible: bool) -> Vec<f32> {
    use crate::polycube::Primitive;
    let nl = CONTEXT_DIM / NUM_CELLS;
    let mut labels = [Primitive::Null; NUM_CELLS];
    let mut withheld = [false; NUM_CELLS];
    for n in 0..NUM_CELLS {
        let row = &one_hot[n * nl..(n + 1) * nl];
        match row.iter().position(|&v| v > 0.5) {
            Some(l) => labels[n] = Primitive::from_label(l as u8).unwrap_or(Primitive::Null),
            None => {
                labels[n] = Primitive::Cube;
                withheld[n] = true;
            }
        }
    }
    let ctx = crate::context::Context { labels };
    let mut rng = crate::geometry::rng::seeded_rng(PRIOR_SEED, 0);
    let mut cells = if visible {
        crate::diffusion::dataset::sample_cells_visible(&ctx, 1.0, &mut rng)
    } else {
        crate::diffusion::dataset::sample_cells(&ctx, 1.0, &mut rng)
    };
    for n in 0..NUM_CELLS {
        if withheld[n] {
            cells[n].clear();
        }
    }
    crate::polycube::tensor::layout(&cells)
}

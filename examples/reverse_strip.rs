//! The paper's reverse-process figure: a strip of rendered point clouds from t = 500
//! to t = 0 for one context, starting from pure noise (the full ancestral sampler),
//! and a second strip for the default strided sampler started from the forward-noised
//! exact polycube at its default start step.
//! Args: [labels] [out.png] [weights]
use sddpm::context::Context;
use sddpm::diffusion::sample::{reverse_diffusion, SamplerOptions};
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::export::render::{render, Camera, Canvas, Layer};
use sddpm::geometry::rng::seeded_rng;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::layout;
use sddpm::polycube::NUM_CELLS;
use sddpm::search::verify::active_points;

fn cloud(t: &[f32], ctx: &Context) -> (Vec<[f64; 3]>, Vec<[u8; 3]>) {
    let palette = [[40u8, 90, 170], [200, 90, 40], [50, 150, 70], [160, 60, 150], [120, 120, 120], [200, 170, 40]];
    let mut pts = Vec::new();
    let mut cols = Vec::new();
    for n in 0..NUM_CELLS {
        if ctx.labels[n] == sddpm::polycube::Primitive::Null {
            continue;
        }
        let p = active_points(t, n, 1e-4);
        cols.extend(std::iter::repeat(palette[n % palette.len()]).take(p.len()));
        pts.extend(p);
    }
    (pts, cols)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let ctx = Context::parse(args.get(1).map(String::as_str).unwrap_or("THC+Z,cube,0,0,0,0,0,0,0,0,0,0")).unwrap();
    let out = args.get(2).cloned().unwrap_or("reverse_diffusion.png".into());
    let model = match args.get(3) {
        Some(p) => Model::from_file(std::path::Path::new(p), Backend::Flex).unwrap(),
        None => Model::default_model().unwrap(),
    };
    let mut rng = seeded_rng(7, 0);
    let x0 = layout(&sample_cells(&ctx, 1.0, &mut rng));
    let (w, h) = (220usize, 220usize);
    let frames = 6;
    let mut rows: Vec<Vec<Canvas>> = Vec::new();
    for (steps, start) in [(0usize, 0usize), (50, 200)] {
        let t_start = if start == 0 { 500 } else { start };
        let n_steps = if steps == 0 { t_start } else { steps };
        let keep = (n_steps / (frames - 1)).max(1);
        let o = SamplerOptions { steps, start_step: start, keep_every: keep, seed: 3, ..Default::default() };
        let r = reverse_diffusion(&model, &[x0.clone()], &[ctx], &o, &mut NoProgress).unwrap();
        let traj = &r.trajectory[0];
        let mut row = Vec::new();
        for (t, x) in traj.iter() {
            let (p, c) = cloud(x, &ctx);
            let canvas = render(&[Layer::Points { points: &p, colours: &c, radius_px: 1.5 }], w, h, Camera::default()).unwrap();
            println!("row {} t = {t}: {} points", rows.len(), p.len());
            row.push(canvas);
        }
        rows.push(row);
    }
    let cols = rows.iter().map(|r| r.len()).max().unwrap();
    let (tw, th) = (cols * w, rows.len() * h);
    let mut buf = vec![255u8; tw * th * 3];
    for (ri, row) in rows.iter().enumerate() {
        for (ci, c) in row.iter().enumerate() {
            for y in 0..h {
                for x in 0..w {
                    let px = c.rgb[y * w + x];
                    let o = ((ri * h + y) * tw + ci * w + x) * 3;
                    buf[o..o + 3].copy_from_slice(&px);
                }
            }
        }
    }
    image::save_buffer(&out, &buf, tw as u32, th as u32, image::ColorType::Rgb8).unwrap();
    println!("wrote {out}");
}

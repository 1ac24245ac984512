//! Developer probe: plain Chamfer and PCD of a diffused cell (and of its exact
//! samples) to every template. Args: weights steps labels [start_step]
use sddpm::context::Context;
use sddpm::diffusion::sample::{reverse_diffusion, SamplerOptions};
use sddpm::diffusion::{Backend, Model};
use sddpm::error::NoProgress;
use sddpm::geometry::rng::seeded_rng;
use sddpm::context::context_frame;
use sddpm::diffusion::dataset::sample_cells;
use sddpm::polycube::tensor::layout;
use sddpm::polycube::Primitive;
use sddpm::search::verify::{active_points, cached_templates, chamfer, local_points, pcd};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = Model::from_file(std::path::Path::new(&args[1]), Backend::Flex).unwrap();
    let steps: usize = args[2].parse().unwrap();
    let ctx = Context::parse(&args[3]).unwrap();
    let start_step: usize = args.get(4).map(|v| v.parse().unwrap()).unwrap_or(0);
    let refine_passes: usize = args.get(5).map(|v| v.parse().unwrap()).unwrap_or(0);
    let refine_t: usize = args.get(6).map(|v| v.parse().unwrap()).unwrap_or(20);
    let mut rng = seeded_rng(5, 5);
    let exact = sample_cells(&ctx, 1.0, &mut rng);
    let x0 = layout(&exact);
    let frame = context_frame(&ctx).unwrap();
    let cond = args.get(7).map(|c| Context::parse(c).unwrap()).unwrap_or(ctx);
    let clip_margin: f64 = std::env::var("CLIP").ok().map(|v| v.parse().unwrap()).unwrap_or(-1.0);
    let out = reverse_diffusion(&model, &[x0.clone()], &[cond], &SamplerOptions { steps, start_step, refine_passes, refine_t, clip_margin, ..Default::default() }, &mut NoProgress).unwrap();
    let tpl = cached_templates(2048);
    {
        use sddpm::export::render::{render_png, Camera, Layer};
        for (name, t) in [("exact", &x0), ("output", &out.tensors[0])] {
            let pts: Vec<[f64; 3]> = ctx.occupied().flat_map(|n| active_points(t, n, 1e-4)).collect();
            let cols = vec![[40u8, 80, 160]];
            render_png(std::path::Path::new(&format!("/tmp/debug_{name}.png")), &[Layer::Points { points: &pts, colours: &cols, radius_px: 2.0 }], 400, 400, Camera::default()).unwrap();
        }
    }
    for n in ctx.occupied() {
        for (name, t) in [("exact", &x0), ("output", &out.tensors[0])] {
            let pts = active_points(t, n, 1e-4);
            let loc = local_points(&pts, frame.scale);
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for p in &loc { for a in 0..3 { lo[a] = lo[a].min(p[a]); hi[a] = hi[a].max(p[a]); } }
            print!("{name} cell {n} ({} pts, span {:.2} {:.2} {:.2}):", loc.len(), hi[0]-lo[0], hi[1]-lo[1], hi[2]-lo[2]);
            for q in Primitive::solids() {
                print!(" {}={:.4}/{:.4}", q.name(), chamfer(&loc, &tpl[q.label() as usize]), pcd(&loc, &tpl[q.label() as usize], 0.01, 2.0));
            }
            println!();
        }
    }
}

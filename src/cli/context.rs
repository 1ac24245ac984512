//! `sddpm context --labels L [--json]`: one-hot vector, assembled genus, validity, reason.

use sddpm::context::Context;
use sddpm::Result;
use serde_json::json;

#[derive(clap::Args, Debug)]
pub struct ContextArgs {
    /// 12 comma-separated labels in cell-index order (0..10 or names: null, cube, THC+Z, ...).
    #[arg(long, allow_hyphen_values = true)]
    pub labels: String,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
    /// Also write the assembled polycube surface as OBJ.
    #[arg(long)]
    pub obj: Option<std::path::PathBuf>,
}

pub fn run(a: &ContextArgs) -> Result<i32> {
    let ctx = Context::parse(&a.labels)?;
    let v = ctx.validity();
    if let Some(p) = &a.obj {
        sddpm::export::obj::write_polycube_obj(p, &ctx)?;
    }
    let one_hot: Vec<u8> = ctx.one_hot().iter().map(|&x| x as u8).collect();
    if a.json {
        println!(
            "{}",
            json!({
                "labels": ctx.label_values(),
                "names": ctx.labels.iter().map(|p| p.name()).collect::<Vec<_>>(),
                "one_hot": one_hot,
                "valid": v.valid,
                "genus": v.genus,
                "euler": v.euler,
                "voxels": v.voxels,
                "reason": v.reason,
            })
        );
    } else {
        println!("labels:  {}", ctx.names());
        println!("one-hot: {}", one_hot.iter().map(|b| b.to_string()).collect::<String>());
        println!("valid:   {}", if v.valid { "yes" } else { "no" });
        match v.genus {
            Some(g) => println!("genus:   {g}"),
            None => println!("genus:   - (Euler characteristic of the boundary {})", v.euler),
        }
        if let Some(r) = &v.reason {
            println!("reason:  {r}");
        }
    }
    Ok(if v.valid { 0 } else { 2 })
}

//! Plot the TCV pass rate against training epochs from the CSV files that
//! benches/tcv_vs_epoch.sh writes (one series per file; the input's own exact
//! polycube, "input_tcv", as the ceiling).
//!
//! `cargo run --release --example plot_tcv_curve -- OUT.png NAME=FILE.csv [NAME=FILE.csv ...]`
use sddpm::export::plot::{line_png, Series};

fn main() -> sddpm::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 3 {
        eprintln!("usage: plot_tcv_curve OUT.png NAME=FILE.csv ...");
        std::process::exit(2);
    }
    let mut names = Vec::new();
    let mut data = Vec::new();
    let mut ceiling = Vec::new();
    for arg in &a[2..] {
        let (name, file) = arg.rsplit_once('=').unwrap_or((arg.as_str(), arg.as_str()));
        let text = std::fs::read_to_string(file).map_err(|e| sddpm::error::Error::io(file, e))?;
        let mut pts = Vec::new();
        for line in text.lines().skip(1) {
            // epoch,cases,gocc,tcv,input_tcv,mean_chamfer,seconds
            let f: Vec<&str> = line.split(',').collect();
            let (Ok(e), Ok(n), Ok(t)) = (f[0].parse::<f64>(), f[1].parse::<f64>(), f[3].parse::<f64>()) else { continue };
            pts.push((e, 100.0 * t / n));
            if let Some(Ok(i)) = f.get(4).map(|s| s.parse::<f64>()) {
                if ceiling.iter().all(|c: &(f64, f64)| c.0 != e) {
                    ceiling.push((e, 100.0 * i / n));
                }
            }
        }
        names.push(name.to_string());
        data.push(pts);
    }
    let mut series: Vec<Series> = names.iter().zip(data).map(|(n, p)| Series { name: n, points: p }).collect();
    if !ceiling.is_empty() {
        ceiling.sort_by(|x, y| x.0.total_cmp(&y.0));
        series.push(Series { name: "the inputs' own polycubes", points: ceiling });
    }
    line_png(std::path::Path::new(&a[1]), &series, "TCV pass rate on held-in synthetic inputs", "epoch", "TCV passed (%)", false)
}

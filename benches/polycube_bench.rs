//! Polycube domain benchmarks: validity + genus of assemblies, the 4,095 cube-only
//! occupancy patterns, constraint enumeration on the full grid, and data-set
//! generation. Run: `cargo bench --bench polycube_bench` (prints a Markdown table).

use sddpm::context::{Constraints, Context};
use sddpm::diffusion::dataset::{generate, DatasetConfig};
use sddpm::polycube::{assemble, check, Primitive};
use std::time::Instant;

fn main() {
    // Assembly check throughput.
    let ctx = Context::parse("THC+Z,cube,BHC+X,cube,THC+Y,BHC-Z,cube,THC+Z,cube,0,cube,BHC+Y").unwrap();
    let n = 20_000;
    let t = Instant::now();
    let mut g = 0;
    for _ in 0..n {
        g += check(&assemble(&ctx.labels)).genus.unwrap_or(0);
    }
    let per = t.elapsed().as_secs_f64() / n as f64;
    println!("assembly + validity + genus of a 11-cell context: {:.1} us (genus {})", per * 1e6, g / n as i64);

    let t = Instant::now();
    let mut valid = 0;
    for mask in 1u32..4096 {
        let mut l = [Primitive::Null; 12];
        for (k, s) in l.iter_mut().enumerate() {
            if mask >> k & 1 == 1 {
                *s = Primitive::Cube;
            }
        }
        valid += check(&assemble(&l)).valid as usize;
    }
    println!("4,095 cube-only occupancy patterns: {valid} valid, {:.1} ms", t.elapsed().as_secs_f64() * 1e3);

    println!();
    println!("| constraints | valid contexts | genus filter | kept | time (s) |");
    println!("|---|---:|---|---:|---:|");
    let sets: Vec<(&str, Constraints)> = vec![
        ("1 THC, rest free, full grid", Constraints { thc: Some(1), cube: Some(0), bhc: Some(0), ..Default::default() }),
        ("3 cubes", Constraints { cube: Some(3), thc: Some(0), bhc: Some(0), ..Default::default() }),
        ("2 cubes + 1 THC + 1 BHC", Constraints { cube: Some(2), thc: Some(1), bhc: Some(1), ..Default::default() }),
        ("3 THC, X row (cells 0-2)", Constraints { thc: Some(3), cube: Some(0), bhc: Some(0), ..Default::default() }.with_mask("111000000000").unwrap()),
        ("4 cells: 2 THC + 2 cubes", Constraints { cube: Some(2), thc: Some(2), bhc: Some(0), ..Default::default() }),
        ("6 cells: 3 cubes + 2 THC + 1 BHC", Constraints { cube: Some(3), thc: Some(2), bhc: Some(1), ..Default::default() }),
        ("12 cells: 6 cubes + 6 THC, full mask", Constraints { cube: Some(6), thc: Some(6), bhc: Some(0), ..Default::default() }.with_mask("111111111111").unwrap()),
    ];
    for (name, c) in sets {
        let t = Instant::now();
        let all = c.enumerate().unwrap();
        let secs = t.elapsed().as_secs_f64();
        let mut hist = std::collections::BTreeMap::new();
        for x in &all {
            *hist.entry(x.validity().genus.unwrap()).or_insert(0usize) += 1;
        }
        let g3 = hist.get(&3).copied().unwrap_or(0);
        println!("| {name} | {} | genus counts {:?} | genus 3: {g3} | {secs:.3} |", all.len(), hist);
    }
    println!();
    let t = Instant::now();
    let d = generate(&DatasetConfig::default());
    println!("data set (seed 42, {} samples): {:.2} s", d.len(), t.elapsed().as_secs_f64());
}

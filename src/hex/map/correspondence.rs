//! The diffusion correspondence as a seed of the surface map
//! (`MapOptions::use_correspondence`).

use crate::geometry::vec3::*;

/// Nearest-neighbour displacement field from the diffusion correspondence
/// (polycube point -> input point, normalised frame), on a bucket grid.
#[derive(Debug, Clone)]
pub struct Correspondence {
    src: Vec<[f64; 3]>,
    disp: Vec<[f64; 3]>,
    lo: [f64; 3],
    cell: f64,
    dims: [usize; 3],
    buckets: Vec<Vec<u32>>,
}

impl Correspondence {
    /// None when there are no usable pairs (non-finite pairs are dropped).
    pub fn new(pairs: &[([f64; 3], [f64; 3])]) -> Option<Correspondence> {
        let good: Vec<&([f64; 3], [f64; 3])> =
            pairs.iter().filter(|(a, b)| a.iter().chain(b.iter()).all(|v| v.is_finite())).collect();
        if good.len() < 8 {
            return None;
        }
        let src: Vec<[f64; 3]> = good.iter().map(|p| p.0).collect();
        let disp: Vec<[f64; 3]> = good.iter().map(|p| sub(p.1, p.0)).collect();
        let bb = crate::geometry::Aabb::of_points(&src);
        let size = bb.size();
        let vol = (size[0].max(1e-9)) * (size[1].max(1e-9)) * (size[2].max(1e-9));
        let cell = (vol / (src.len() as f64 / 4.0)).cbrt().max(1e-6);
        let dims = size.map(|s| ((s / cell).floor() as usize + 1).min(256));
        let mut buckets = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let lo = bb.min;
        for (i, p) in src.iter().enumerate() {
            let c: [usize; 3] = std::array::from_fn(|a| (((p[a] - lo[a]) / cell).floor().max(0.0) as usize).min(dims[a] - 1));
            buckets[c[0] + dims[0] * (c[1] + dims[1] * c[2])].push(i as u32);
        }
        Some(Correspondence { src, disp, lo, cell, dims, buckets })
    }

    /// Inverse-distance weighted displacement of the k nearest pairs.
    pub fn displacement(&self, p: [f64; 3], k: usize) -> [f64; 3] {
        let c: [i64; 3] = std::array::from_fn(|a| ((p[a] - self.lo[a]) / self.cell).floor() as i64);
        let mut found: Vec<(f64, u32)> = Vec::new();
        let mut r = 0i64;
        loop {
            for z in c[2] - r..=c[2] + r {
                for y in c[1] - r..=c[1] + r {
                    for x in c[0] - r..=c[0] + r {
                        let on_shell = (x - c[0]).abs() == r || (y - c[1]).abs() == r || (z - c[2]).abs() == r;
                        if !on_shell {
                            continue;
                        }
                        if x < 0 || y < 0 || z < 0 {
                            continue;
                        }
                        let (xu, yu, zu) = (x as usize, y as usize, z as usize);
                        if xu >= self.dims[0] || yu >= self.dims[1] || zu >= self.dims[2] {
                            continue;
                        }
                        for &i in &self.buckets[xu + self.dims[0] * (yu + self.dims[1] * zu)] {
                            found.push((dist2(p, self.src[i as usize]), i));
                        }
                    }
                }
            }
            // every point within distance r * cell has been seen
            let reach = (r as f64) * self.cell;
            found.sort_by(|a, b| a.0.total_cmp(&b.0));
            if found.len() >= k && found[k - 1].0.sqrt() <= reach {
                break;
            }
            if r as usize > self.dims.iter().copied().max().unwrap_or(1) + 2 {
                break;
            }
            r += 1;
        }
        found.truncate(k);
        let mut w_sum = 0.0;
        let mut acc = [0.0; 3];
        for (d2, i) in found {
            let w = 1.0 / (d2 + 1e-12);
            w_sum += w;
            acc = add(acc, scale(self.disp[i as usize], w));
        }
        if w_sum > 0.0 {
            scale(acc, 1.0 / w_sum)
        } else {
            [0.0; 3]
        }
    }
}

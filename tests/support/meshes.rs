//! Small hex meshes built in code and the uniform 1-to-8 subdivision of a hex
//! mesh: fixtures of the spline tests and benchmarks, which include this file
//! (`#[path = "support/meshes.rs"] mod meshes;`); not part of the library.
#![allow(dead_code)]

use sddpm::hex::HexMesh;
use std::collections::HashMap;

/// An nx x ny x nz block of unit-spaced hexes scaled to `size`, origin at 0.
pub fn block(n: [usize; 3], size: [f64; 3]) -> HexMesh {
    let id = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let mut nodes = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                nodes.push([
                    size[0] * i as f64 / n[0] as f64,
                    size[1] * j as f64 / n[1] as f64,
                    size[2] * k as f64 / n[2] as f64,
                ]);
            }
        }
    }
    let mut elements = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                elements.push([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ]);
            }
        }
    }
    HexMesh { nodes, elements }
}

/// Welds points by rounding, returning node ids.
struct Welder {
    map: HashMap<[i64; 3], u32>,
    nodes: Vec<[f64; 3]>,
}

impl Welder {
    fn new() -> Self {
        Welder { map: HashMap::new(), nodes: Vec::new() }
    }
    fn id(&mut self, p: [f64; 3]) -> u32 {
        let k = p.map(|x| (x * 1e9).round() as i64);
        if let Some(&i) = self.map.get(&k) {
            return i;
        }
        let i = self.nodes.len() as u32;
        self.nodes.push(p);
        self.map.insert(k, i);
        i
    }
}

/// A disk of `valence` sectors around the z axis, each sector an m x m grid of
/// quads, extruded into `layers` layers of height 1/layers: the interior
/// vertical edges on the axis have valence `valence` (extraordinary unless 4).
/// With layers >= 3 the middle axis edges are interior extraordinary edges.
pub fn extraordinary_edge(valence: usize, m: usize, layers: usize) -> HexMesh {
    assert!(valence >= 3 && m >= 1 && layers >= 1);
    let n = valence as f64;
    let sector = 2.0 * std::f64::consts::PI / n;
    // corner point of sector s: bisector, radius chosen so the quad is convex
    let a = |s: usize| {
        let t = sector * s as f64;
        [t.cos(), t.sin()]
    };
    let c = |s: usize| {
        let t = sector * (s as f64 + 0.5);
        let r = 1.0 / (sector / 2.0).cos().max(0.5) * 0.9 + 0.1;
        [r * t.cos(), r * t.sin()]
    };
    let mut w = Welder::new();
    let mut elements = Vec::new();
    for s in 0..valence {
        let (p0, p1, p2, p3) = ([0.0, 0.0], a(s), c(s), a((s + 1) % valence));
        let bil = |x: f64, y: f64| {
            let mut q = [0.0; 2];
            for i in 0..2 {
                q[i] = (1.0 - x) * (1.0 - y) * p0[i] + x * (1.0 - y) * p1[i] + x * y * p2[i] + (1.0 - x) * y * p3[i];
            }
            q
        };
        for l in 0..layers {
            for j in 0..m {
                for i in 0..m {
                    let mut ids = [0u32; 8];
                    let quad = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
                    for (h, z) in [(0usize, l), (1, l + 1)] {
                        for (q, &(x, y)) in quad.iter().enumerate() {
                            let p = bil(x as f64 / m as f64, y as f64 / m as f64);
                            ids[4 * h + q] = w.id([p[0], p[1], z as f64 / layers as f64]);
                        }
                    }
                    elements.push(ids);
                }
            }
        }
    }
    HexMesh { nodes: w.nodes, elements }
}

/// Uniform subdivision: every hex into 8, new nodes at edge midpoints, face
/// centres and element centres (trilinear positions).
pub fn subdivide(hex: &HexMesh) -> HexMesh {
    use sddpm::spline::topology::BITS_OF_VTK;
    let mut nodes = hex.nodes.clone();
    let mut cache: HashMap<Vec<u32>, u32> = HashMap::new();
    let mut elements = Vec::with_capacity(hex.elements.len() * 8);
    for el in &hex.elements {
        // 3x3x3 lattice of node ids: index (a, b, c) in 0..3
        let mut lat = [[[0u32; 3]; 3]; 3];
        for (c, plane) in lat.iter_mut().enumerate() {
            for (b, row) in plane.iter_mut().enumerate() {
                for (a, slot) in row.iter_mut().enumerate() {
                    let idx = [a, b, c];
                    // corners of the sub-entity: all corners whose bits agree where idx is 0 or 2
                    let mut corners: Vec<u32> = Vec::new();
                    for (n, bits) in BITS_OF_VTK.iter().enumerate() {
                        if (0..3).all(|d| idx[d] == 1 || bits[d] * 2 == idx[d]) {
                            corners.push(el[n]);
                        }
                    }
                    if corners.len() == 1 {
                        *slot = corners[0];
                        continue;
                    }
                    let mut key = corners.clone();
                    key.sort_unstable();
                    *slot = *cache.entry(key).or_insert_with(|| {
                        let mut p = [0.0; 3];
                        for &v in &corners {
                            for i in 0..3 {
                                p[i] += hex.nodes[v as usize][i];
                            }
                        }
                        let s = 1.0 / corners.len() as f64;
                        nodes.push(p.map(|x| x * s));
                        (nodes.len() - 1) as u32
                    });
                }
            }
        }
        for c in 0..8usize {
            let cb = BITS_OF_VTK[c];
            let mut ids = [0u32; 8];
            for (n, bits) in BITS_OF_VTK.iter().enumerate() {
                ids[n] = lat[cb[2] + bits[2]][cb[1] + bits[1]][cb[0] + bits[0]];
            }
            elements.push(ids);
        }
    }
    HexMesh { nodes, elements }
}

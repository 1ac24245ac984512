//! The indexed triangle mesh every stage works on. Reading, welding and checking
//! one is the mesh stage's (`mesh`); what is here needs nothing but the
//! arrays.

/// An indexed triangle mesh in f64. Triangles are counter-clockwise seen from outside
/// once the mesh has passed the checks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Drop vertices no triangle uses, keeping the order of the others. Returns how many went.
    pub fn remove_unreferenced(&mut self) -> usize {
        let mut used = vec![false; self.vertices.len()];
        for t in &self.triangles {
            for &v in t {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
        }
        let removed = used.iter().filter(|u| !**u).count();
        if removed == 0 {
            return 0;
        }
        let mut new_id = vec![u32::MAX; self.vertices.len()];
        let mut kept = Vec::with_capacity(self.vertices.len() - removed);
        for (i, p) in self.vertices.iter().enumerate() {
            if used[i] {
                new_id[i] = kept.len() as u32;
                kept.push(*p);
            }
        }
        self.vertices = kept;
        for t in &mut self.triangles {
            for v in t.iter_mut() {
                *v = new_id[*v as usize];
            }
        }
        removed
    }
}

/// Meshes built in code for the unit tests of every stage.
#[cfg(test)]
pub(crate) mod tests {
    use super::TriMesh;

    /// Closed outward surface of a set of unit voxels on an nx x ny x nz lattice.
    pub(crate) fn voxels(n: [usize; 3], filled: impl Fn(usize, usize, usize) -> bool) -> TriMesh {
        let id = |x: usize, y: usize, z: usize| (x + (n[0] + 1) * (y + (n[1] + 1) * z)) as u32;
        let mut vertices = Vec::new();
        for z in 0..=n[2] {
            for y in 0..=n[1] {
                for x in 0..=n[0] {
                    vertices.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let on = |x: isize, y: isize, z: isize| {
            x >= 0 && y >= 0 && z >= 0 && (x as usize) < n[0] && (y as usize) < n[1] && (z as usize) < n[2] && filled(x as usize, y as usize, z as usize)
        };
        let mut triangles = Vec::new();
        for z in 0..n[2] {
            for y in 0..n[1] {
                for x in 0..n[0] {
                    if !filled(x, y, z) {
                        continue;
                    }
                    let (xi, yi, zi) = (x as isize, y as isize, z as isize);
                    // each face as 4 corners counter-clockwise seen from outside
                    let faces: [([isize; 3], [[usize; 3]; 4]); 6] = [
                        ([-1, 0, 0], [[0, 0, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]]),
                        ([1, 0, 0], [[1, 0, 0], [1, 1, 0], [1, 1, 1], [1, 0, 1]]),
                        ([0, -1, 0], [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]]),
                        ([0, 1, 0], [[0, 1, 0], [0, 1, 1], [1, 1, 1], [1, 1, 0]]),
                        ([0, 0, -1], [[0, 0, 0], [0, 1, 0], [1, 1, 0], [1, 0, 0]]),
                        ([0, 0, 1], [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]),
                    ];
                    for (d, c) in faces {
                        if on(xi + d[0], yi + d[1], zi + d[2]) {
                            continue;
                        }
                        let v = c.map(|o| id(x + o[0], y + o[1], z + o[2]));
                        triangles.push([v[0], v[1], v[2]]);
                        triangles.push([v[0], v[2], v[3]]);
                    }
                }
            }
        }
        let mut m = TriMesh { vertices, triangles };
        m.remove_unreferenced();
        m
    }

    /// The box [lo, hi] as 12 outward triangles.
    pub(crate) fn box_mesh(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
        let v: Vec<[f64; 3]> = (0..8)
            .map(|i| [if i & 1 == 0 { lo[0] } else { hi[0] }, if i & 2 == 0 { lo[1] } else { hi[1] }, if i & 4 == 0 { lo[2] } else { hi[2] }])
            .collect();
        // faces (outward, counter-clockwise): quads split into triangles
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let mut t = Vec::new();
        for q in quads {
            t.push([q[0], q[1], q[2]]);
            t.push([q[0], q[2], q[3]]);
        }
        TriMesh { vertices: v, triangles: t }
    }
}

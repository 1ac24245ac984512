//! Voxel sets and the voxeliser: a closed surface filled on a regular voxel lattice
//! (a voxel is inside when at least two of three axis-parallel rays through its
//! centre cross the surface an odd number of times before reaching it, which
//! tolerates the odd self-intersection or grazing hit), each inside voxel split into
//! six Kuhn tetrahedra, and the solid fraction of each voxel. The automated mode's
//! temporary volume (`search::auto`) and the voxel hex mesher
//! (`hex::voxel`) are built on it.
//!
//! Topology of a voxel solid ([`betti`]): its first Betti number b1 (the number of
//! independent tunnels: b1 = b0 + b2 - chi of the closed cubical complex, with
//! 26-connected solid components b0 and 6-connected sealed cavities b2) is its genus.

use super::{Aabb, Bvh, TriMesh};
use crate::error::{Error, Result};

/// A box-shaped lattice of occupied / empty voxels; index x + nx (y + ny z).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct VoxelGrid {
    pub dims: [usize; 3],
    pub occ: Vec<bool>,
}

impl VoxelGrid {
    pub fn empty(dims: [usize; 3]) -> Self {
        VoxelGrid { dims, occ: vec![false; dims[0] * dims[1] * dims[2]] }
    }

    #[inline]
    pub fn idx(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Occupancy at signed coordinates; outside the lattice is empty.
    #[inline]
    pub fn at(&self, x: i64, y: i64, z: i64) -> bool {
        if x < 0 || y < 0 || z < 0 {
            return false;
        }
        let (x, y, z) = (x as usize, y as usize, z as usize);
        if x >= self.dims[0] || y >= self.dims[1] || z >= self.dims[2] {
            return false;
        }
        self.occ[self.idx(x, y, z)]
    }

    pub fn count(&self) -> usize {
        self.occ.iter().filter(|&&b| b).count()
    }

    /// Coordinates of voxel number `i`.
    #[inline]
    pub fn coords(&self, i: usize) -> [usize; 3] {
        [i % self.dims[0], (i / self.dims[0]) % self.dims[1], i / (self.dims[0] * self.dims[1])]
    }
}
/// A voxelised solid over an axis-aligned box.
#[derive(Debug, Clone)]
pub struct VoxelVolume {
    pub lo: [f64; 3],
    pub h: f64,
    pub grid: VoxelGrid,
}

impl VoxelVolume {
    pub fn voxel_centre(&self, x: usize, y: usize, z: usize) -> [f64; 3] {
        [self.lo[0] + (x as f64 + 0.5) * self.h, self.lo[1] + (y as f64 + 0.5) * self.h, self.lo[2] + (z as f64 + 0.5) * self.h]
    }

    /// Volume of the inside voxels (= of their Kuhn tetrahedra).
    pub fn volume(&self) -> f64 {
        self.grid.count() as f64 * self.h.powi(3)
    }

    /// Number of tetrahedra of the temporary volume (6 per inside voxel).
    pub fn tetrahedra(&self) -> usize {
        6 * self.grid.count()
    }
}

fn ray_hits(mesh: &TriMesh, bvh: &Bvh, axis: usize, o: [f64; 3], lo: f64, hi: f64) -> Vec<f64> {
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut bmin = o;
    let mut bmax = o;
    bmin[axis] = lo;
    bmax[axis] = hi;
    let bb = Aabb { min: bmin, max: bmax };
    let mut hits = Vec::new();
    bvh.for_each_overlap(&bb, |t| {
        let [a, b, c] = mesh.triangles[t as usize].map(|i| mesh.vertices[i as usize]);
        // 2D point-in-triangle in the (u, w) plane, then the hit coordinate along axis.
        let (pu, pw) = (o[u], o[w]);
        let d = (b[u] - a[u]) * (c[w] - a[w]) - (c[u] - a[u]) * (b[w] - a[w]);
        if d.abs() < 1e-300 {
            return;
        }
        let l1 = ((b[u] - pu) * (c[w] - pw) - (c[u] - pu) * (b[w] - pw)) / d;
        let l2 = ((c[u] - pu) * (a[w] - pw) - (a[u] - pu) * (c[w] - pw)) / d;
        let l3 = 1.0 - l1 - l2;
        if l1 >= 0.0 && l2 >= 0.0 && l3 >= 0.0 {
            hits.push(l1 * a[axis] + l2 * b[axis] + l3 * c[axis]);
        }
    });
    hits.sort_by(f64::total_cmp);
    hits
}

/// Fill the aligned surface on a lattice with `resolution` voxels along its longest
/// bounding-box edge.
pub fn voxelize(mesh: &TriMesh, resolution: usize) -> Result<VoxelVolume> {
    let (lo, h, dims) = uniform_lattice(mesh, resolution)?;
    Ok(VoxelVolume { lo, h, grid: voxelize_on(mesh, lo, h, dims) })
}

/// The lattice [`voxelize`] fills: `resolution` (clamped to 4..=512) voxels of
/// size `h` along the longest bounding-box edge, centred on the box; its first
/// corner, voxel size and voxel counts.
pub fn uniform_lattice(mesh: &TriMesh, resolution: usize) -> Result<([f64; 3], f64, [usize; 3])> {
    let resolution = resolution.clamp(4, 512);
    let bb = Aabb::of_points(&mesh.vertices);
    let size = bb.size();
    let longest = size[0].max(size[1]).max(size[2]);
    if !(longest > 0.0) || !longest.is_finite() {
        return Err(Error::InvalidMesh("cannot voxelise a surface without extent".into()));
    }
    let h = longest / resolution as f64;
    let dims: [usize; 3] = std::array::from_fn(|a| ((size[a] / h).ceil() as usize).max(1));
    let lo: [f64; 3] = std::array::from_fn(|a| bb.centre()[a] - dims[a] as f64 * h / 2.0);
    Ok((lo, h, dims))
}

/// Fill the aligned surface on the lattice of `dims` voxels of size `h` from `lo`
/// (a voxel is inside when its centre is inside along at least two of the three
/// axis rays through it).
pub fn voxelize_on(mesh: &TriMesh, lo: [f64; 3], h: f64, dims: [usize; 3]) -> VoxelGrid {
    let bvh = Bvh::new(mesh);
    let mut votes = vec![0u8; dims[0] * dims[1] * dims[2]];
    let idx = |x: usize, y: usize, z: usize| x + dims[0] * (y + dims[1] * z);
    // Irrational offsets keep rays off mesh edges and vertices in practice.
    let jitter = [1.0e-7 * std::f64::consts::PI, 1.0e-7 * std::f64::consts::E, 1.0e-7 * std::f64::consts::SQRT_2];
    for axis in 0..3 {
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        for j in 0..dims[u] {
            for k in 0..dims[w] {
                let mut o = [0.0; 3];
                o[u] = lo[u] + (j as f64 + 0.5) * h + jitter[u];
                o[w] = lo[w] + (k as f64 + 0.5) * h + jitter[w];
                let hits = ray_hits(mesh, &bvh, axis, o, lo[axis] - h, lo[axis] + (dims[axis] as f64 + 1.0) * h);
                let mut next = 0;
                for i in 0..dims[axis] {
                    let c = lo[axis] + (i as f64 + 0.5) * h;
                    while next < hits.len() && hits[next] < c {
                        next += 1;
                    }
                    if next % 2 == 1 {
                        let mut p = [0usize; 3];
                        p[axis] = i;
                        p[u] = j;
                        p[w] = k;
                        votes[idx(p[0], p[1], p[2])] += 1;
                    }
                }
            }
        }
    }
    let occ = votes.iter().map(|&v| v >= 2).collect();
    VoxelGrid { dims, occ }
}

/// The fraction of each voxel of `vol`'s lattice that lies inside `mesh`, from
/// `k` x `k` rays along z per voxel column (the inside length of each ray, between
/// alternate crossings, summed per voxel). Same indexing as `vol.grid.occ`.
pub fn solid_fractions(mesh: &TriMesh, vol: &VoxelVolume, k: usize) -> Vec<f32> {
    let dims = vol.grid.dims;
    let (lo, h) = (vol.lo, vol.h);
    let k = k.max(1);
    let bvh = Bvh::new(mesh);
    let mut frac = vec![0f32; dims[0] * dims[1] * dims[2]];
    let weight = 1.0 / (k * k) as f64 / h;
    let jitter = [1.0e-7 * std::f64::consts::PI, 1.0e-7 * std::f64::consts::E];
    let (zlo, zhi) = (lo[2] - h, lo[2] + (dims[2] as f64 + 1.0) * h);
    for y in 0..dims[1] {
        for x in 0..dims[0] {
            let mut column = vec![0f64; dims[2]];
            for a in 0..k {
                for b in 0..k {
                    let o = [lo[0] + (x as f64 + (a as f64 + 0.5) / k as f64) * h + jitter[0], lo[1] + (y as f64 + (b as f64 + 0.5) / k as f64) * h + jitter[1], 0.0];
                    let hits = ray_hits(mesh, &bvh, 2, o, zlo, zhi);
                    for pair in hits.chunks_exact(2) {
                        let (s, e) = ((pair[0] - lo[2]) / h, (pair[1] - lo[2]) / h);
                        let (i0, i1) = (s.floor().max(0.0) as usize, (e.ceil().max(0.0) as usize).min(dims[2]));
                        for (i, c) in column.iter_mut().enumerate().take(i1).skip(i0) {
                            let overlap = (e.min(i as f64 + 1.0) - s.max(i as f64)).max(0.0);
                            *c += overlap * h;
                        }
                    }
                }
            }
            for (z, c) in column.into_iter().enumerate() {
                frac[x + dims[0] * (y + dims[1] * z)] = (c * weight) as f32;
            }
        }
    }
    frac
}

/// The 3x3x3 majority filter of a voxel set: a voxel is solid when at least 14 of
/// the 27 voxels around it (itself included; outside the lattice is empty) are.
/// It removes the one-voxel bridges and pits that surface noise leaves in a
/// voxelisation, which would otherwise count as tunnels and cavities, and keeps
/// features three voxels wide.
pub fn majority(g: &VoxelGrid) -> VoxelGrid {
    let [nx, ny, nz] = g.dims;
    let mut out = VoxelGrid::empty(g.dims);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let mut n = 0;
                for dz in -1i64..=1 {
                    for dy in -1i64..=1 {
                        for dx in -1i64..=1 {
                            n += usize::from(g.at(x as i64 + dx, y as i64 + dy, z as i64 + dz));
                        }
                    }
                }
                let i = out.idx(x, y, z);
                out.occ[i] = n >= 14;
            }
        }
    }
    out
}

/// First Betti number b1 of a voxel solid, plus b0 and b2 (see the module docs).
pub fn betti(g: &VoxelGrid) -> (usize, usize, i64) {
    let [nx, ny, nz] = g.dims;
    if g.count() == 0 {
        return (0, 0, 0);
    }
    let at = |x: i64, y: i64, z: i64| g.at(x, y, z);
    // chi of the closed cubical complex: count lattice cells touched by a solid voxel.
    let (mut v, mut e, mut f) = (0i64, 0i64, 0i64);
    let c = g.count() as i64;
    for z in 0..=nz as i64 {
        for y in 0..=ny as i64 {
            for x in 0..=nx as i64 {
                // vertex (x,y,z): any of its 8 voxels solid
                if (0..8).any(|o| at(x - 1 + (o & 1), y - 1 + ((o >> 1) & 1), z - 1 + ((o >> 2) & 1))) {
                    v += 1;
                }
                // edges from (x,y,z) along +x, +y, +z: any of the 4 voxels around solid
                for ax in 0..3 {
                    let lim = [nx as i64, ny as i64, nz as i64];
                    let p = [x, y, z];
                    if p[ax] >= lim[ax] {
                        continue;
                    }
                    let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
                    let touched = (0..4).any(|o| {
                        let mut q = p;
                        q[u] -= o & 1;
                        q[w] -= (o >> 1) & 1;
                        at(q[0], q[1], q[2])
                    });
                    if touched {
                        e += 1;
                    }
                    // faces spanned by axes u, w at (x,y,z): the 2 voxels on either side along ax
                }
                // faces perpendicular to ax at (x,y,z): spanned by the other two axes
                for ax in 0..3 {
                    let lim = [nx as i64, ny as i64, nz as i64];
                    let p = [x, y, z];
                    let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
                    if p[u] >= lim[u] || p[w] >= lim[w] {
                        continue;
                    }
                    let mut q = p;
                    let a = at(q[0], q[1], q[2]);
                    q[ax] -= 1;
                    let b = at(q[0], q[1], q[2]);
                    if a || b {
                        f += 1;
                    }
                }
            }
        }
    }
    let chi = v - e + f - c;
    // b0: 26-connected solid components.
    let mut seen = vec![false; g.occ.len()];
    let mut b0 = 0usize;
    let mut stack = Vec::new();
    for s in 0..g.occ.len() {
        if !g.occ[s] || seen[s] {
            continue;
        }
        b0 += 1;
        seen[s] = true;
        stack.push(s);
        while let Some(i) = stack.pop() {
            let [x, y, z] = g.coords(i);
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (a, b, cc) = (x as i64 + dx, y as i64 + dy, z as i64 + dz);
                        if at(a, b, cc) {
                            let j = g.idx(a as usize, b as usize, cc as usize);
                            if !seen[j] {
                                seen[j] = true;
                                stack.push(j);
                            }
                        }
                    }
                }
            }
        }
    }
    // b2: 6-connected empty regions not reaching the outside.
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    let mut out = vec![false; px * py * pz];
    let pid = |x: usize, y: usize, z: usize| x + px * (y + py * z);
    let solid = |x: usize, y: usize, z: usize| at(x as i64 - 1, y as i64 - 1, z as i64 - 1);
    let mut st = vec![0usize];
    out[0] = true;
    let mut reached = 1usize;
    while let Some(i) = st.pop() {
        let (x, y, z) = (i % px, (i / px) % py, i / (px * py));
        for d in [[1i64, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]] {
            let (a, b, cc) = (x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]);
            if a < 0 || b < 0 || cc < 0 || a >= px as i64 || b >= py as i64 || cc >= pz as i64 {
                continue;
            }
            let j = pid(a as usize, b as usize, cc as usize);
            if !out[j] && !solid(a as usize, b as usize, cc as usize) {
                out[j] = true;
                reached += 1;
                st.push(j);
            }
        }
    }
    let empty_total = px * py * pz - g.count();
    let mut b2 = 0usize;
    if reached < empty_total {
        // count sealed empty components
        let mut mark = out.clone();
        for z in 1..pz - 1 {
            for y in 1..py - 1 {
                for x in 1..px - 1 {
                    let i = pid(x, y, z);
                    if mark[i] || solid(x, y, z) {
                        continue;
                    }
                    b2 += 1;
                    mark[i] = true;
                    st.push(i);
                    while let Some(k) = st.pop() {
                        let (a0, b0_, c0) = (k % px, (k / px) % py, k / (px * py));
                        for d in [[1i64, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]] {
                            let (a, b, cc) = (a0 as i64 + d[0], b0_ as i64 + d[1], c0 as i64 + d[2]);
                            let j = pid(a as usize, b as usize, cc as usize);
                            if !mark[j] && !solid(a as usize, b as usize, cc as usize) {
                                mark[j] = true;
                                st.push(j);
                            }
                        }
                    }
                }
            }
        }
    }
    let b1 = b0 as i64 + b2 as i64 - chi;
    (b0, b2, b1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::trimesh::tests::box_mesh;

    #[test]
    fn solid_fractions_of_a_box() {
        // a box whose top lies at three quarters of a voxel: those voxels are 3/4 full
        let b = box_mesh([0.0, 0.0, 0.0], [1.0, 1.0, 0.55]);
        let vol = voxelize(&b, 10).unwrap();
        assert_eq!(vol.grid.dims, [10, 10, 6]);
        let f = solid_fractions(&b, &vol, 4);
        for z in 0..6 {
            let want = if z == 0 || z == 5 { 0.75 } else { 1.0 };
            for i in 0..100 {
                assert!((f[i + 100 * z] as f64 - want).abs() < 1e-6, "z {z}: {} vs {want}", f[i + 100 * z]);
            }
        }
    }

    #[test]
    fn the_majority_filter_drops_a_one_voxel_bridge_and_keeps_a_ring() {
        // a square ring, walls 3 voxels thick around a 3x3 hole, 3 voxels tall
        // (genus 1), with a one-voxel handle standing on its top (genus 2)
        let mut g = VoxelGrid::empty([9, 9, 7]);
        let mut set = |x: usize, y: usize, z: usize| {
            let i = g.idx(x, y, z);
            g.occ[i] = true;
        };
        for z in 1..4 {
            for y in 0..9 {
                for x in 0..9 {
                    if !((3..6).contains(&x) && (3..6).contains(&y)) {
                        set(x, y, z);
                    }
                }
            }
        }
        set(2, 1, 4);
        set(6, 1, 4);
        for x in 2..7 {
            set(x, 1, 5);
        }
        assert_eq!(betti(&g).2, 2);
        let m = majority(&g);
        assert_eq!(betti(&m).2, 1);
        assert!(m.occ[m.idx(4, 1, 2)] && !m.occ[m.idx(4, 4, 2)] && !m.occ[m.idx(4, 1, 5)]);
    }

    #[test]
    fn betti_of_a_sealed_cavity() {
        // A sealed cavity: b2 = 1, b1 = 0.
        let mut g = VoxelGrid::empty([3, 3, 3]);
        g.occ.iter_mut().for_each(|v| *v = true);
        let c = g.idx(1, 1, 1);
        g.occ[c] = false;
        assert_eq!(betti(&g), (1, 1, 0));
    }
}

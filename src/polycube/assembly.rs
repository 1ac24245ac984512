//! Assembly of a labelled grid into a solid on the 9x6x6 sub-voxel lattice, its
//! boundary surface, its genus and its validity. Everything here is computed from
//! the voxel set, never from label arithmetic.

use super::primitive::{cell_coords, cell_index, Primitive, GRID, LATTICE, NUM_CELLS, SUB};
use crate::geometry::VoxelGrid;
use crate::mesh::TriMesh;

/// The voxel set of a labelling of the 12 cells on the 9x6x6 lattice.
pub fn assemble(labels: &[Primitive; NUM_CELLS]) -> VoxelGrid {
    let mut g = VoxelGrid::empty(LATTICE);
    for (n, p) in labels.iter().enumerate() {
        if *p == Primitive::Null {
            continue;
        }
        let [i, j, k] = cell_coords(n);
        let sv = p.subvoxels();
        for c in 0..SUB {
            for b in 0..SUB {
                for a in 0..SUB {
                    if sv[a + 3 * b + 9 * c] {
                        let ix = g.idx(i * SUB + a, j * SUB + b, k * SUB + c);
                        g.occ[ix] = true;
                    }
                }
            }
        }
    }
    g
}

/// One primitive alone on a 3x3x3 lattice (the template solid of TCV).
pub fn single(p: Primitive) -> VoxelGrid {
    VoxelGrid { dims: [SUB; 3], occ: p.subvoxels().to_vec() }
}

/// What the validity check measured, and why an assembly is invalid.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Validity {
    pub valid: bool,
    /// Genus of the boundary surface, known when the assembly is valid.
    pub genus: Option<i64>,
    /// V - E + F of the boundary (counting each lattice point / edge once).
    pub euler: i64,
    pub voxels: usize,
    /// Face-connected pieces of the solid.
    pub components: usize,
    /// Sealed empty regions inside the solid.
    pub cavities: usize,
    /// Lattice edges where two voxels meet only along the edge.
    pub edge_contacts: usize,
    /// Lattice points where the boundary is pinched (voxels meeting only at a corner).
    pub vertex_contacts: usize,
    /// Human-readable reason when invalid (names cells in the 0-based index order).
    pub reason: Option<String>,
}

fn cell_name_of_voxel(v: [usize; 3], dims: [usize; 3]) -> Option<String> {
    if dims == LATTICE {
        let (i, j, k) = (v[0] / SUB, v[1] / SUB, v[2] / SUB);
        Some(format!("cell {} ({},{},{})", cell_index(i, j, k), i, j, k))
    } else {
        None
    }
}

fn describe_voxels(vs: &[[usize; 3]], dims: [usize; 3]) -> String {
    let mut names: Vec<String> = vs.iter().filter_map(|v| cell_name_of_voxel(*v, dims)).collect();
    names.sort();
    names.dedup();
    if names.is_empty() {
        format!("sub-voxels {:?}", vs)
    } else {
        names.join(" and ")
    }
}

const NB6: [[i64; 3]; 6] = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];

/// Check one voxel set: connectivity, manifoldness, cavities, Euler characteristic, genus.
pub fn check(g: &VoxelGrid) -> Validity {
    let [nx, ny, nz] = g.dims;
    let n = g.count();
    let mut v = Validity {
        valid: false,
        genus: None,
        euler: 0,
        voxels: n,
        components: 0,
        cavities: 0,
        edge_contacts: 0,
        vertex_contacts: 0,
        reason: None,
    };
    if n == 0 {
        v.reason = Some("no cell is occupied".into());
        return v;
    }
    let mut reasons: Vec<String> = Vec::new();

    // Face-connected components of the solid.
    let mut comp = vec![usize::MAX; g.occ.len()];
    let mut stack = Vec::new();
    let mut comp_first: Vec<[usize; 3]> = Vec::new();
    for start in 0..g.occ.len() {
        if !g.occ[start] || comp[start] != usize::MAX {
            continue;
        }
        let c = comp_first.len();
        comp_first.push(g.coords(start));
        comp[start] = c;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let [x, y, z] = g.coords(i);
            for d in NB6 {
                let (a, b, cc) = (x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]);
                if g.at(a, b, cc) {
                    let j = g.idx(a as usize, b as usize, cc as usize);
                    if comp[j] == usize::MAX {
                        comp[j] = c;
                        stack.push(j);
                    }
                }
            }
        }
    }
    v.components = comp_first.len();
    if v.components > 1 {
        let mut pieces = Vec::new();
        for c in 0..v.components {
            let cells: Vec<[usize; 3]> = (0..g.occ.len()).filter(|&i| comp[i] == c).map(|i| g.coords(i)).collect();
            pieces.push(describe_voxels(&cells, g.dims));
        }
        reasons.push(format!(
            "the solid falls into {} separate pieces: [{}]",
            v.components,
            pieces.join("] [")
        ));
    }

    // Edge contacts: around each interior lattice edge, 4 voxels in a diagonal pattern.
    // Edge along axis `ax` at lattice point p: the 4 voxels p - e_u*{0,1} - e_v*{0,1}.
    let mut first_edge: Option<Vec<[usize; 3]>> = None;
    for ax in 0..3 {
        let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
        let mut p = [0i64; 3];
        let lim = [nx as i64, ny as i64, nz as i64];
        for s in 0..lim[ax] {
            for a in 0..=lim[u] {
                for b in 0..=lim[w] {
                    p[ax] = s;
                    p[u] = a;
                    p[w] = b;
                    let vox = |du: i64, dw: i64| {
                        let mut q = p;
                        q[u] -= du;
                        q[w] -= dw;
                        (g.at(q[0], q[1], q[2]), q)
                    };
                    let (o00, q00) = vox(0, 0);
                    let (o11, q11) = vox(1, 1);
                    let (o01, q01) = vox(0, 1);
                    let (o10, q10) = vox(1, 0);
                    let diag = (o00 && o11 && !o01 && !o10) || (!o00 && !o11 && o01 && o10);
                    if diag {
                        v.edge_contacts += 1;
                        if first_edge.is_none() {
                            let occ: Vec<[usize; 3]> = [(o00, q00), (o11, q11), (o01, q01), (o10, q10)]
                                .iter()
                                .filter(|(o, _)| *o)
                                .map(|(_, q)| [q[0] as usize, q[1] as usize, q[2] as usize])
                                .collect();
                            first_edge = Some(occ);
                        }
                    }
                }
            }
        }
    }
    if let Some(vs) = first_edge {
        reasons.push(format!(
            "{} sub-voxel edge(s) where solid meets solid only along an edge, first between {}",
            v.edge_contacts,
            describe_voxels(&vs, g.dims)
        ));
    }

    // Vertex contacts: the 2x2x2 block around a lattice point must have both its solid
    // and its empty octants face-connected (within the block).
    let mut first_vertex: Option<Vec<[usize; 3]>> = None;
    for pz in 0..=nz as i64 {
        for py in 0..=ny as i64 {
            for px in 0..=nx as i64 {
                let pattern = octant_pattern(g, px, py, pz);
                // a pinch not already explained by an edge contact
                if !vertex_tables().pinched[pattern as usize] {
                    continue;
                }
                v.vertex_contacts += 1;
                if first_vertex.is_none() {
                    let vs: Vec<[usize; 3]> = (0..8i64)
                        .filter(|&o| pattern >> o & 1 == 1)
                        .map(|o| [(px - 1 + (o & 1)) as usize, (py - 1 + ((o >> 1) & 1)) as usize, (pz - 1 + ((o >> 2) & 1)) as usize])
                        .collect();
                    first_vertex = Some(vs);
                }
            }
        }
    }
    if let Some(vs) = first_vertex {
        reasons.push(format!(
            "{} lattice point(s) where the boundary is pinched (solid or empty space meeting only at a corner), first at {}",
            v.vertex_contacts,
            describe_voxels(&vs, g.dims)
        ));
    }

    // Sealed cavities: empty voxels not reachable from outside (padded lattice, 6-neighbourhood).
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    let pidx = |x: usize, y: usize, z: usize| x + px * (y + py * z);
    let solid_p = |x: usize, y: usize, z: usize| g.at(x as i64 - 1, y as i64 - 1, z as i64 - 1);
    let mut seen = vec![false; px * py * pz];
    stack.clear();
    seen[0] = true;
    stack.push(0usize);
    while let Some(i) = stack.pop() {
        let (x, y, z) = (i % px, (i / px) % py, i / (px * py));
        for d in NB6 {
            let (a, b, c) = (x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]);
            if a < 0 || b < 0 || c < 0 || a >= px as i64 || b >= py as i64 || c >= pz as i64 {
                continue;
            }
            let (a, b, c) = (a as usize, b as usize, c as usize);
            let j = pidx(a, b, c);
            if !seen[j] && !solid_p(a, b, c) {
                seen[j] = true;
                stack.push(j);
            }
        }
    }
    let mut cavity_voxels = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if !g.occ[g.idx(x, y, z)] && !seen[pidx(x + 1, y + 1, z + 1)] {
                    cavity_voxels.push([x, y, z]);
                }
            }
        }
    }
    if !cavity_voxels.is_empty() {
        // Count cavities as face-connected groups of sealed empty voxels.
        let mut mark = vec![false; g.occ.len()];
        let mut count = 0;
        for &s in &cavity_voxels {
            let si = g.idx(s[0], s[1], s[2]);
            if mark[si] {
                continue;
            }
            count += 1;
            mark[si] = true;
            stack.push(si);
            while let Some(i) = stack.pop() {
                let [x, y, z] = g.coords(i);
                for d in NB6 {
                    let (a, b, c) = (x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]);
                    if a < 0 || b < 0 || c < 0 || a >= nx as i64 || b >= ny as i64 || c >= nz as i64 {
                        continue;
                    }
                    let j = g.idx(a as usize, b as usize, c as usize);
                    if !g.occ[j] && !mark[j] {
                        mark[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        v.cavities = count;
        reasons.push(format!(
            "{} sealed cavit{} inside the solid (a hole closed off by a neighbour), in {}",
            count,
            if count == 1 { "y" } else { "ies" },
            describe_voxels(&cavity_voxels, g.dims)
        ));
    }

    v.euler = boundary_euler(g);
    if reasons.is_empty() {
        v.valid = true;
        v.genus = Some((2 - v.euler) / 2);
    } else {
        v.reason = Some(reasons.join("; "));
    }
    v
}

/// The 2x2x2 block of voxels around lattice point (px, py, pz) as 8 bits (bit o =
/// octant o, o's bit 0 = x, 1 = y, 2 = z; voxel (px - 1 + dx, ...)).
fn octant_pattern(g: &VoxelGrid, px: i64, py: i64, pz: i64) -> u8 {
    let mut pattern = 0u8;
    for o in 0..8 {
        if g.at(px - 1 + (o & 1), py - 1 + ((o >> 1) & 1), pz - 1 + ((o >> 2) & 1)) {
            pattern |= 1 << o;
        }
    }
    pattern
}

/// Per 2x2x2 octant pattern: whether the lattice point is a pinch [`check`] counts
/// (solid or empty octants not face-connected, not explained by an edge contact),
/// and 8 x its share of the Euler characteristic of the solid (see [`euler_solid`]).
struct VertexTables {
    pinched: [bool; 256],
    euler8: [i8; 256],
}

fn vertex_tables() -> &'static VertexTables {
    static T: std::sync::OnceLock<VertexTables> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let mut t = VertexTables { pinched: [false; 256], euler8: [0; 256] };
        for p in 0..256usize {
            let oct: [bool; 8] = std::array::from_fn(|o| p >> o & 1 == 1);
            let any = |f: &dyn Fn(usize) -> bool| (0..8).any(|o| oct[o] && f(o));
            t.pinched[p] = p != 0 && p != 255 && (!octants_connected(&oct, true) || !octants_connected(&oct, false)) && !block_has_edge_diagonal(&oct);
            // the point itself (1), its 6 half-edges (-1/2 each, an edge along `ax`
            // towards side `s` touches the 4 octants with bit ax = s), its 12 quarter
            // faces (+1/4 each, the face normal to `ax` in quadrant (su, sw) touches the
            // 2 octants with those bits), its 8 eighth voxels (-1/8 each); each counted
            // when one of the cells it touches is solid
            let mut e = if p != 0 { 8 } else { 0 };
            for ax in 0..3 {
                for s in 0..2 {
                    if any(&|o| o >> ax & 1 == s) {
                        e -= 4;
                    }
                }
                let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
                for su in 0..2 {
                    for sw in 0..2 {
                        if any(&|o| o >> u & 1 == su && o >> w & 1 == sw) {
                            e += 2;
                        }
                    }
                }
            }
            e -= p.count_ones() as i32;
            t.euler8[p] = e as i8;
        }
        t
    })
}

/// Euler characteristic of the solid (the union of the closed voxels), summed from
/// each lattice point's 2x2x2 pattern. For a valid solid (one component, no cavity,
/// manifold boundary: a handlebody) it is 1 - genus, so a set whose value says
/// another genus can be passed over without the full [`check`].
pub fn euler_solid(g: &VoxelGrid) -> i64 {
    let [nx, ny, nz] = g.dims.map(|d| d as i64);
    let t = vertex_tables();
    let mut sum = 0i64;
    for pz in 0..=nz {
        for py in 0..=ny {
            for px in 0..=nx {
                sum += t.euler8[octant_pattern(g, px, py, pz) as usize] as i64;
            }
        }
    }
    debug_assert_eq!(sum % 8, 0);
    sum / 8
}

/// Octants of a 2x2x2 block (bit 0 = x, 1 = y, 2 = z) of the given value: are they face-connected?
fn octants_connected(oct: &[bool; 8], value: bool) -> bool {
    let members: Vec<usize> = (0..8).filter(|&o| oct[o] == value).collect();
    if members.len() <= 1 {
        return true;
    }
    let mut seen = [false; 8];
    let mut stack = vec![members[0]];
    seen[members[0]] = true;
    let mut reached = 1;
    while let Some(o) = stack.pop() {
        for bit in 0..3 {
            let q = o ^ (1 << bit);
            if oct[q] == value && !seen[q] {
                seen[q] = true;
                reached += 1;
                stack.push(q);
            }
        }
    }
    reached == members.len()
}

/// Does the 2x2x2 block contain a diagonal (edge-contact) 2x2 face pattern?
fn block_has_edge_diagonal(oct: &[bool; 8]) -> bool {
    // The 6 faces of the block... we need the 2x2 squares around the 6 half-edges
    // through the block centre: fixing one axis bit pattern pair.
    for ax in 0..3 {
        for fixed in 0..2 {
            // the four octants with bit `ax` == fixed form a 2x2 square around an edge along ax? No:
            // the square perpendicular to axis ax at layer `fixed` surrounds the edge from the
            // centre point along ax towards that side.
            let mut sq = [false; 4];
            let mut t = 0;
            for o in 0..8 {
                if (o >> ax) & 1 == fixed {
                    sq[t] = oct[o];
                    t += 1;
                }
            }
            // sq order: remaining two bits in increasing order -> (0,0),(1,0),(0,1),(1,1)
            let diag = (sq[0] && sq[3] && !sq[1] && !sq[2]) || (!sq[0] && !sq[3] && sq[1] && sq[2]);
            if diag {
                return true;
            }
        }
    }
    false
}

/// V - E + F of the boundary of a voxel set, each lattice point / edge / face counted once.
pub fn boundary_euler(g: &VoxelGrid) -> i64 {
    let [nx, ny, nz] = g.dims.map(|d| d as i64);
    let mut f = 0i64;
    // Faces: between voxel p and p + e_ax.
    for ax in 0..3 {
        for z in -1..nz {
            for y in -1..ny {
                for x in -1..nx {
                    let mut q = [x, y, z];
                    if [x, y, z].iter().enumerate().any(|(i, &c)| i != ax && c < 0) {
                        continue;
                    }
                    let a = g.at(q[0], q[1], q[2]);
                    q[ax] += 1;
                    let b = g.at(q[0], q[1], q[2]);
                    if a != b {
                        f += 1;
                    }
                }
            }
        }
    }
    let mut e = 0i64;
    for ax in 0..3 {
        let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
        let lim = [nx, ny, nz];
        let mut p = [0i64; 3];
        for s in 0..lim[ax] {
            for a in 0..=lim[u] {
                for b in 0..=lim[w] {
                    p[ax] = s;
                    p[u] = a;
                    p[w] = b;
                    let mut vals = [false; 4];
                    for (t, (du, dw)) in [(0, 0), (1, 0), (0, 1), (1, 1)].iter().enumerate() {
                        let mut q = p;
                        q[u] -= du;
                        q[w] -= dw;
                        vals[t] = g.at(q[0], q[1], q[2]);
                    }
                    if vals.iter().any(|&b| b != vals[0]) {
                        e += 1;
                    }
                }
            }
        }
    }
    let mut vcount = 0i64;
    for pz in 0..=nz {
        for py in 0..=ny {
            for px in 0..=nx {
                let first = g.at(px - 1, py - 1, pz - 1);
                let mut differs = false;
                for o in 1..8 {
                    let val = g.at(px - 1 + (o & 1), py - 1 + ((o >> 1) & 1), pz - 1 + ((o >> 2) & 1));
                    if val != first {
                        differs = true;
                        break;
                    }
                }
                if differs {
                    vcount += 1;
                }
            }
        }
    }
    vcount - e + f
}

/// A quad surface: vertices in grid units (one cell = 1), quads counter-clockwise seen from outside.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuadMesh {
    pub vertices: Vec<[f64; 3]>,
    pub quads: Vec<[u32; 4]>,
    /// For each quad: the voxel it bounds (lattice coordinates) and its outward axis (0..6: +X,-X,+Y,-Y,+Z,-Z).
    pub quad_voxel: Vec<([usize; 3], u8)>,
}

impl QuadMesh {
    /// Split every quad into two triangles (diagonal 0-2).
    pub fn to_trimesh(&self) -> TriMesh {
        let mut triangles = Vec::with_capacity(self.quads.len() * 2);
        for q in &self.quads {
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
        TriMesh { vertices: self.vertices.clone(), triangles }
    }

    pub fn area(&self) -> f64 {
        // Every quad is an axis-aligned square of the lattice.
        let s = self
            .quads
            .first()
            .map(|q| {
                let a = self.vertices[q[0] as usize];
                let b = self.vertices[q[1] as usize];
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .unwrap_or(0.0);
        self.quads.len() as f64 * s * s
    }
}

/// The boundary of a voxel set as a quad mesh in grid units (voxel edge = 1/3).
/// Lattice points are shared, so the mesh is closed wherever the solid is; at a
/// non-manifold edge or vertex it is non-manifold (as the solid is).
pub fn boundary(g: &VoxelGrid) -> QuadMesh {
    let [nx, ny, nz] = g.dims;
    let (lx, ly) = (nx + 1, ny + 1);
    let mut id = vec![u32::MAX; (nx + 1) * (ny + 1) * (nz + 1)];
    let mut m = QuadMesh::default();
    let h = 1.0 / SUB as f64;
    let mut vid = |m: &mut QuadMesh, p: [usize; 3]| -> u32 {
        let k = p[0] + lx * (p[1] + ly * p[2]);
        if id[k] == u32::MAX {
            id[k] = m.vertices.len() as u32;
            m.vertices.push([p[0] as f64 * h, p[1] as f64 * h, p[2] as f64 * h]);
        }
        id[k]
    };
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if !g.occ[g.idx(x, y, z)] {
                    continue;
                }
                for (dir, d) in NB6.iter().enumerate() {
                    if g.at(x as i64 + d[0], y as i64 + d[1], z as i64 + d[2]) {
                        continue;
                    }
                    let ax = dir / 2;
                    let positive = dir % 2 == 0;
                    let (u, w) = ((ax + 1) % 3, (ax + 2) % 3);
                    let mut base = [x, y, z];
                    if positive {
                        base[ax] += 1;
                    }
                    let corner = |du: usize, dw: usize| {
                        let mut p = base;
                        p[u] += du;
                        p[w] += dw;
                        p
                    };
                    let cs = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                    let mut q = [0u32; 4];
                    for (t, c) in cs.iter().enumerate() {
                        q[t] = vid(&mut m, *c);
                    }
                    if !positive {
                        q = [q[0], q[3], q[2], q[1]];
                    }
                    m.quads.push(q);
                    m.quad_voxel.push(([x, y, z], dir as u8));
                }
            }
        }
    }
    m
}

/// The faces of cell `n` that touch an occupied neighbour in `labels`: bit 2a is the
/// face at the low end of axis a, bit 2a + 1 the face at its high end.
pub fn shared_faces(labels: &[Primitive; NUM_CELLS], n: usize) -> u8 {
    let c = cell_coords(n);
    let mut bits = 0u8;
    for a in 0..3 {
        for (side, step) in [(0u8, -1i64), (1, 1)] {
            let mut d = c.map(|v| v as i64);
            d[a] += step;
            let limit = GRID[a] as i64;
            if d[a] >= 0 && d[a] < limit {
                let m = cell_index(d[0] as usize, d[1] as usize, d[2] as usize);
                if labels[m] != Primitive::Null {
                    bits |= 1 << (2 * a as u8 + side);
                }
            }
        }
    }
    bits
}

/// Bounding box of the occupied cells of a labelling, in grid units: (min, max) corners.
pub fn occupied_cell_box(labels: &[Primitive; NUM_CELLS]) -> Option<([usize; 3], [usize; 3])> {
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    let mut any = false;
    for (n, p) in labels.iter().enumerate() {
        if *p == Primitive::Null {
            continue;
        }
        any = true;
        let c = cell_coords(n);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a]);
            hi[a] = hi[a].max(c[a] + 1);
        }
    }
    any.then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use Primitive::*;

    #[test]
    fn betti_of_primitives_and_of_the_voxelised_torus() {
        use crate::geometry::voxel::{betti, voxelize};
        for p in Primitive::solids() {
            let (b0, b2, b1) = betti(&single(p));
            assert_eq!((b0, b2, b1), (1, 0, p.standalone_genus()), "{p}");
        }
        // The voxelised picture-frame torus (THC+Z alone): genus 1, volume close to the surface's.
        let mut labels = [Null; NUM_CELLS];
        labels[0] = ThcZ;
        let m = boundary(&assemble(&labels)).to_trimesh();
        let vol = voxelize(&m, 30).unwrap();
        assert!((vol.volume() - 24.0 / 27.0).abs() < 1e-9, "{}", vol.volume());
        let (b0, b2, b1) = betti(&vol.grid);
        assert_eq!((b0, b2, b1), (1, 0, 1));
    }

    #[test]
    fn the_tables_agree_with_the_direct_counts_on_random_assemblies() {
        // Euler characteristic from the lattice-point table against V - E + F - C
        // counted directly, and 1 - chi against the genus of every valid assembly
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let all: Vec<Primitive> = (0..11u8).filter_map(Primitive::from_label).filter(|p| *p != Null).collect();
        let (mut valid, mut genera) = (0, std::collections::BTreeSet::new());
        for _ in 0..3000 {
            let mut l = [Null; NUM_CELLS];
            for c in l.iter_mut() {
                if rng.random::<f64>() < 0.6 {
                    *c = all[rng.random_range(0..all.len())];
                }
            }
            let g = assemble(&l);
            let chi = euler_solid(&g);
            // direct count: solid cells of each dimension in the closed union
            let at = |x: i64, y: i64, z: i64| g.at(x, y, z);
            let [nx, ny, nz] = g.dims.map(|d| d as i64);
            let (mut cv, mut ce, mut cf, mut cc) = (0i64, 0i64, 0i64, 0i64);
            for z in 0..=nz {
                for y in 0..=ny {
                    for x in 0..=nx {
                        // voxels touching vertex, edges along a, faces normal to a, voxel
                        let near = |dx: &[i64], dy: &[i64], dz: &[i64]| dx.iter().any(|&i| dy.iter().any(|&j| dz.iter().any(|&k| at(x + i, y + j, z + k))));
                        cv += near(&[-1, 0], &[-1, 0], &[-1, 0]) as i64;
                        ce += near(&[0], &[-1, 0], &[-1, 0]) as i64 + near(&[-1, 0], &[0], &[-1, 0]) as i64 + near(&[-1, 0], &[-1, 0], &[0]) as i64;
                        cf += near(&[-1, 0], &[0], &[0]) as i64 + near(&[0], &[-1, 0], &[0]) as i64 + near(&[0], &[0], &[-1, 0]) as i64;
                        cc += at(x, y, z) as i64;
                    }
                }
            }
            assert_eq!(chi, cv - ce + cf - cc, "{l:?}");
            let v = check(&g);
            if v.valid {
                valid += 1;
                genera.insert(v.genus.unwrap());
                assert_eq!(v.genus, Some(1 - chi), "{l:?}");
            }
        }
        assert!(valid > 100 && genera.len() >= 3, "{valid} valid, genera {genera:?}");
    }

    fn labels(pairs: &[(usize, Primitive)]) -> [Primitive; NUM_CELLS] {
        let mut l = [Null; NUM_CELLS];
        for &(n, p) in pairs {
            l[n] = p;
        }
        l
    }

    #[test]
    fn single_primitives() {
        for p in Primitive::solids() {
            let v = check(&single(p));
            assert!(v.valid, "{p}: {:?}", v.reason);
            assert_eq!(v.genus, Some(p.standalone_genus()), "{p}");
            let v2 = check(&assemble(&labels(&[(4, p)])));
            assert_eq!(v2.genus, Some(p.standalone_genus()));
        }
    }

    #[test]
    fn known_cases() {
        // THC+X with a cube on its -X side: the hole is capped -> blind -> genus 0.
        let v = check(&assemble(&labels(&[(1, ThcX), (0, Cube)])));
        assert!(v.valid, "{:?}", v.reason);
        assert_eq!(v.genus, Some(0));
        // THC+X with cubes on both sides: sealed cavity.
        let v = check(&assemble(&labels(&[(1, ThcX), (0, Cube), (2, Cube)])));
        assert!(!v.valid);
        assert_eq!(v.cavities, 1);
        // Two THC+Z stacked along Z: one longer hole, genus 1.
        let v = check(&assemble(&labels(&[(0, ThcZ), (6, ThcZ)])));
        assert_eq!(v.genus, Some(1));
        // Two THC+X in a row: genus 1.
        let v = check(&assemble(&labels(&[(0, ThcX), (1, ThcX), (2, ThcX)])));
        assert_eq!(v.genus, Some(1));
        // Three THC+Z in a row along X: genus 3.
        let v = check(&assemble(&labels(&[(0, ThcZ), (1, ThcZ), (2, ThcZ)])));
        assert_eq!(v.genus, Some(3));
        // BHC+Z under a cube: sealed cavity -> invalid.
        let v = check(&assemble(&labels(&[(0, BhcPz), (6, Cube)])));
        assert!(!v.valid);
        assert!(v.reason.as_ref().unwrap().contains("cavit"), "{:?}", v.reason);
        // BHC-Z under a cube: the opening faces down, fine.
        let v = check(&assemble(&labels(&[(0, BhcMz), (6, Cube)])));
        assert!(v.valid);
        assert_eq!(v.genus, Some(0));
        // BHC+Z under a BHC-Z: joined blind holes make a sealed cavity.
        let v = check(&assemble(&labels(&[(0, BhcPz), (6, BhcMz)])));
        assert!(!v.valid);
        // BHC+Z under a THC+Z: the hole runs on through the upper cell but the BHC's
        // bottom stays closed -> one deeper blind hole, genus 0.
        let v = check(&assemble(&labels(&[(0, BhcPz), (6, ThcZ)])));
        assert!(v.valid);
        assert_eq!(v.genus, Some(0));
        // A THC+Z column (one hole through two cells) beside a THC+X row capped by the
        // column on its -X end (a blind hole): genus 1.
        let v = check(&assemble(&labels(&[(0, ThcZ), (6, ThcZ), (1, ThcX), (2, ThcX)])));
        assert_eq!(v.genus, Some(1 + 0), "{:?}", v.reason);
        // Two cubes touching only along an edge.
        let v = check(&assemble(&labels(&[(0, Cube), (4, Cube)])));
        assert!(!v.valid);
        assert!(v.edge_contacts > 0);
        assert!(v.reason.as_ref().unwrap().contains("cell 0"), "{:?}", v.reason);
        // Two cubes touching at a corner only.
        let v = check(&assemble(&labels(&[(0, Cube), (10, Cube)])));
        assert!(!v.valid);
        assert!(v.vertex_contacts > 0 || v.components == 2);
        // 2x2x2 block minus two diagonally opposite cells: the two empty cells meet at a vertex.
        let mut l = [Null; NUM_CELLS];
        for n in [0, 1, 3, 4, 6, 7, 9, 10] {
            l[n] = Cube;
        }
        l[0] = Null;
        l[10] = Null;
        let v = check(&assemble(&l));
        assert!(!v.valid, "{v:?}");
        assert!(v.vertex_contacts > 0);
    }

    #[test]
    fn cube_occupancy_patterns() {
        let mut valid = 0;
        for mask in 1u32..4096 {
            let mut l = [Null; NUM_CELLS];
            for (n, slot) in l.iter_mut().enumerate() {
                if mask >> n & 1 == 1 {
                    *slot = Cube;
                }
            }
            let v = check(&assemble(&l));
            if v.valid {
                valid += 1;
                assert_eq!(v.genus, Some(0), "mask {mask:#x}");
            }
        }
        assert_eq!(valid, 1058);
    }

    #[test]
    fn boundary_mesh_is_closed_and_consistent() {
        let g = assemble(&labels(&[(0, ThcZ), (1, Cube), (6, BhcPx)]));
        let q = boundary(&g);
        let v = check(&g);
        let t = q.to_trimesh();
        // Every directed edge appears once, and its reverse once.
        let mut edges = std::collections::HashMap::new();
        for tri in &t.triangles {
            for e in 0..3 {
                *edges.entry((tri[e], tri[(e + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &c) in &edges {
            assert_eq!(c, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1));
        }
        let chi = t.vertices.len() as i64 - edges.len() as i64 / 2 + t.triangles.len() as i64;
        assert_eq!(chi, v.euler);
        // Signed volume = voxel count x (1/3)^3.
        let mut vol = 0.0;
        for tri in &t.triangles {
            let [a, b, c] = tri.map(|i| t.vertices[i as usize]);
            vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
        }
        assert!((vol - g.count() as f64 / 27.0).abs() < 1e-12, "{vol}");
    }
}

/// The occupied voxels cropped to their bounding box, as (dims, sorted coordinates).
fn cropped(g: &VoxelGrid) -> ([usize; 3], Vec<[usize; 3]>) {
    let pts: Vec<[usize; 3]> = (0..g.occ.len()).filter(|&i| g.occ[i]).map(|i| g.coords(i)).collect();
    if pts.is_empty() {
        return ([0; 3], pts);
    }
    let lo: [usize; 3] = std::array::from_fn(|a| pts.iter().map(|p| p[a]).min().unwrap());
    let hi: [usize; 3] = std::array::from_fn(|a| pts.iter().map(|p| p[a]).max().unwrap());
    let mut v: Vec<[usize; 3]> = pts.iter().map(|p| std::array::from_fn(|a| p[a] - lo[a])).collect();
    v.sort();
    (std::array::from_fn(|a| hi[a] - lo[a] + 1), v)
}

/// Are two voxel sets the same solid up to a translation and one of the 24 rotations
/// of the cube? (The criterion for "the same polycube" in the context search.)
pub fn congruent(a: &VoxelGrid, b: &VoxelGrid) -> bool {
    let (da, va) = cropped(a);
    let (db, vb) = cropped(b);
    if va.len() != vb.len() {
        return false;
    }
    for r in super::orientation::rotations() {
        // rotate a's cropped coordinates: new axis k = sign * old axis perm[k]
        let dims: [usize; 3] = std::array::from_fn(|k| da[r.perm[k]]);
        if dims != db {
            continue;
        }
        let mut w: Vec<[usize; 3]> = va
            .iter()
            .map(|p| {
                std::array::from_fn(|k| {
                    let v = p[r.perm[k]];
                    if r.sign[k] > 0 {
                        v
                    } else {
                        da[r.perm[k]] - 1 - v
                    }
                })
            })
            .collect();
        w.sort();
        if w == vb {
            return true;
        }
    }
    false
}

//! The validity check of a voxel set: one face-connected piece, no edge or
//! vertex contact, no sealed cavity; the genus of a valid one from the boundary's
//! Euler characteristic.

use super::euler::{boundary_euler, octant_pattern, vertex_tables};
use super::{cell_index, LATTICE, NB6, SUB};
use crate::geometry::VoxelGrid;

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

/// Check one voxel set: connectivity, manifoldness, cavities, Euler characteristic, genus.
pub fn check(g: &VoxelGrid) -> Validity {
    let voxels = g.count();
    if voxels == 0 {
        return Validity {
            valid: false,
            genus: None,
            euler: 0,
            voxels,
            components: 0,
            cavities: 0,
            edge_contacts: 0,
            vertex_contacts: 0,
            reason: Some("no cell is occupied".into()),
        };
    }
    let (components, pieces) = components(g);
    let (edge_contacts, edges) = edge_contacts(g);
    let (vertex_contacts, pinches) = vertex_contacts(g);
    let (cavities, sealed) = cavities(g);
    let reasons: Vec<String> = [pieces, edges, pinches, sealed].into_iter().flatten().collect();
    let euler = boundary_euler(g);
    let valid = reasons.is_empty();
    Validity {
        valid,
        genus: valid.then_some((2 - euler) / 2),
        euler,
        voxels,
        components,
        cavities,
        edge_contacts,
        vertex_contacts,
        reason: (!valid).then(|| reasons.join("; ")),
    }
}

/// Face-connected components of the solid; more than one is a reason naming the pieces.
fn components(g: &VoxelGrid) -> (usize, Option<String>) {
    let mut comp = vec![usize::MAX; g.occ.len()];
    let mut stack = Vec::new();
    let mut count = 0;
    for start in 0..g.occ.len() {
        if !g.occ[start] || comp[start] != usize::MAX {
            continue;
        }
        let c = count;
        count += 1;
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
    if count <= 1 {
        return (count, None);
    }
    let mut pieces = Vec::new();
    for c in 0..count {
        let cells: Vec<[usize; 3]> = (0..g.occ.len()).filter(|&i| comp[i] == c).map(|i| g.coords(i)).collect();
        pieces.push(describe_voxels(&cells, g.dims));
    }
    (count, Some(format!("the solid falls into {} separate pieces: [{}]", count, pieces.join("] ["))))
}

/// Edge contacts: around each interior lattice edge, 4 voxels in a diagonal pattern.
/// Edge along axis `ax` at lattice point p: the 4 voxels p - e_u*{0,1} - e_v*{0,1}.
/// Any is a reason naming the first.
fn edge_contacts(g: &VoxelGrid) -> (usize, Option<String>) {
    let [nx, ny, nz] = g.dims;
    let mut count = 0;
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
                        count += 1;
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
    let reason = first_edge.map(|vs| format!("{} sub-voxel edge(s) where solid meets solid only along an edge, first between {}", count, describe_voxels(&vs, g.dims)));
    (count, reason)
}

/// Vertex contacts: the 2x2x2 block around a lattice point must have both its solid
/// and its empty octants face-connected (within the block). Any is a reason naming
/// the first.
fn vertex_contacts(g: &VoxelGrid) -> (usize, Option<String>) {
    let [nx, ny, nz] = g.dims;
    let mut count = 0;
    let mut first_vertex: Option<Vec<[usize; 3]>> = None;
    for pz in 0..=nz as i64 {
        for py in 0..=ny as i64 {
            for px in 0..=nx as i64 {
                let pattern = octant_pattern(g, px, py, pz);
                // a pinch not already explained by an edge contact
                if !vertex_tables().pinched[pattern as usize] {
                    continue;
                }
                count += 1;
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
    let reason = first_vertex.map(|vs| {
        format!("{} lattice point(s) where the boundary is pinched (solid or empty space meeting only at a corner), first at {}", count, describe_voxels(&vs, g.dims))
    });
    (count, reason)
}

/// Sealed cavities: face-connected groups of the empty voxels not reachable from
/// outside ([`sealed_voxels`]); any is a reason naming where.
fn cavities(g: &VoxelGrid) -> (usize, Option<String>) {
    let [nx, ny, nz] = g.dims;
    let cavity_voxels = sealed_voxels(g);
    if cavity_voxels.is_empty() {
        return (0, None);
    }
    let mut stack = Vec::new();
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
    let reason = format!(
        "{} sealed cavit{} inside the solid (a hole closed off by a neighbour), in {}",
        count,
        if count == 1 { "y" } else { "ies" },
        describe_voxels(&cavity_voxels, g.dims)
    );
    (count, Some(reason))
}

/// The empty voxels not reachable from outside (padded lattice, 6-neighbourhood).
fn sealed_voxels(g: &VoxelGrid) -> Vec<[usize; 3]> {
    let [nx, ny, nz] = g.dims;
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    let pidx = |x: usize, y: usize, z: usize| x + px * (y + py * z);
    let solid_p = |x: usize, y: usize, z: usize| g.at(x as i64 - 1, y as i64 - 1, z as i64 - 1);
    let mut seen = vec![false; px * py * pz];
    let mut stack = vec![0usize];
    seen[0] = true;
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
    cavity_voxels
}

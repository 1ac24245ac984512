//! Euler characteristics of a voxel set from its lattice points: each point's
//! 2x2x2 octant pattern, tabulated once (the solid's share of the Euler
//! characteristic, and whether the point is a pinch), and the boundary's
//! V - E + F counted directly.

use crate::geometry::VoxelGrid;

/// The 2x2x2 block of voxels around lattice point (px, py, pz) as 8 bits (bit o =
/// octant o, o's bit 0 = x, 1 = y, 2 = z; voxel (px - 1 + dx, ...)).
pub(super) fn octant_pattern(g: &VoxelGrid, px: i64, py: i64, pz: i64) -> u8 {
    let mut pattern = 0u8;
    for o in 0..8 {
        if g.at(px - 1 + (o & 1), py - 1 + ((o >> 1) & 1), pz - 1 + ((o >> 2) & 1)) {
            pattern |= 1 << o;
        }
    }
    pattern
}

/// Per 2x2x2 octant pattern: whether the lattice point is a pinch [`check`](super::check) counts
/// (solid or empty octants not face-connected, not explained by an edge contact),
/// and 8 x its share of the Euler characteristic of the solid (see [`euler_solid`]).
pub(super) struct VertexTables {
    pub pinched: [bool; 256],
    pub euler8: [i8; 256],
}

pub(super) fn vertex_tables() -> &'static VertexTables {
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
/// another genus can be passed over without the full [`check`](super::check).
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

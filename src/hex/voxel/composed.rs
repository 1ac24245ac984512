//! Well-composed voxel sets: no two voxels that share only an edge or a vertex,
//! so that the boundary of the set is a 2-manifold.

use crate::geometry::VoxelGrid;

/// Make a voxel set well-composed by filling voxels: in every 2 x 2 square two
/// diagonal voxels alone (occupied or empty), and in every 2 x 2 x 2 block two
/// antipodal voxels alone, are the configurations whose boundary is not a manifold.
/// Filling only adds volume, so the loop ends. Returns the voxels filled.
pub fn make_well_composed(g: &mut VoxelGrid) -> usize {
    make_well_composed_where(g, &|_| true)
}

/// [`make_well_composed`] filling only the voxels `allow` admits (a configuration
/// whose voxels to fill it admits none of stays).
pub fn make_well_composed_where(g: &mut VoxelGrid, allow: &dyn Fn([usize; 3]) -> bool) -> usize {
    let [nx, ny, nz] = g.dims;
    let mut filled = 0;
    let inside = |x: i64, y: i64, z: i64| x >= 0 && y >= 0 && z >= 0 && (x as usize) < nx && (y as usize) < ny && (z as usize) < nz && allow([x as usize, y as usize, z as usize]);
    for _round in 0..64 {
        let mut changed = 0;
        for z in -1..nz as i64 {
            for y in -1..ny as i64 {
                for x in -1..nx as i64 {
                    // the block's corners, index bit 0 = +x, bit 1 = +y, bit 2 = +z
                    let c = |k: usize| [x + (k & 1) as i64, y + ((k >> 1) & 1) as i64, z + ((k >> 2) & 1) as i64];
                    let occ: [bool; 8] = std::array::from_fn(|k| {
                        let p = c(k);
                        g.at(p[0], p[1], p[2])
                    });
                    let mut fill: Option<usize> = None;
                    // 2 x 2 squares of the block (its six faces): diagonal pairs
                    'faces: for axis in 0..3 {
                        for side in 0..2 {
                            let ks: Vec<usize> = (0..8).filter(|&k| (k >> axis) & 1 == side).collect();
                            // ks in order: the two free bits enumerate a square; diagonal = ks[0]/ks[3], ks[1]/ks[2]
                            let (a, b, cc, d) = (ks[0], ks[1], ks[2], ks[3]);
                            if occ[a] == occ[d] && occ[b] == occ[cc] && occ[a] != occ[b] {
                                // fill an empty voxel of the square that lies in the grid
                                let empties = if occ[a] { [b, cc] } else { [a, d] };
                                fill = empties.into_iter().find(|&k| {
                                    let p = c(k);
                                    inside(p[0], p[1], p[2])
                                });
                                if fill.is_some() {
                                    break 'faces;
                                }
                            }
                        }
                    }
                    if fill.is_none() {
                        let n = occ.iter().filter(|&&o| o).count();
                        for k in 0..8 {
                            let anti = 7 - k;
                            let lone_pair = n == 2 && occ[k] && occ[anti];
                            let lone_hole = n == 6 && !occ[k] && !occ[anti];
                            if lone_pair {
                                // connect them through a face neighbour of k
                                fill = [k ^ 1, k ^ 2, k ^ 4].into_iter().find(|&j| {
                                    let p = c(j);
                                    inside(p[0], p[1], p[2])
                                });
                            } else if lone_hole {
                                fill = [k, anti].into_iter().find(|&j| {
                                    let p = c(j);
                                    inside(p[0], p[1], p[2])
                                });
                            }
                            if fill.is_some() {
                                break;
                            }
                        }
                    }
                    if let Some(k) = fill {
                        let p = c(k);
                        let i = g.idx(p[0] as usize, p[1] as usize, p[2] as usize);
                        if !g.occ[i] {
                            g.occ[i] = true;
                            changed += 1;
                        }
                    }
                }
            }
        }
        filled += changed;
        if changed == 0 {
            break;
        }
    }
    filled
}

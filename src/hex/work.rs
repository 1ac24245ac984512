//! The state the node-moving steps share: the mesh being improved ([`Work`]),
//! what ties each node to the input ([`Role`]), the mapped lattice mesh a level or
//! a voxel lattice hands to the quality steps ([`Level`]), and the node-local
//! quality measures every step evaluates its moves with.
//!
//! Every node move keeps its constraint: interior nodes move freely, surface nodes
//! slide in the tangent plane and are projected back onto the input ([`slide`]),
//! curve nodes slide along their feature curve, corner nodes never move.

use super::grid::LatticeHex;
use super::quality::{scaled_jacobian, DEGENERATE};
use super::surface::Surface;
use super::topology::Csr;
use super::HexMesh;
use crate::geometry::vec3::*;

/// What constrains a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    Interior,
    /// On the input surface, free to slide on it.
    Free,
    /// On input feature curve `c`.
    Curve(u32),
    /// Fixed at input vertex `v` (a feature corner).
    Corner(u32),
}

impl Role {
    pub fn on_boundary(self) -> bool {
        !matches!(self, Role::Interior)
    }
}

/// Surface attachment of a boundary node: its triangle on the surface.
pub type Attach = u32;

/// A mesh being improved, with what ties its nodes to the input.
#[derive(Debug, Clone)]
pub struct Work {
    pub mesh: HexMesh,
    pub role: Vec<Role>,
    pub attach: Vec<Attach>,
    /// Neighbours along the feature curve (curve nodes only).
    pub curve_nb: Vec<Vec<u32>>,
    /// Boundary-surface neighbours (boundary nodes only).
    pub bgraph: Csr,
    /// Edge neighbours.
    pub nbr: Csr,
    /// Node -> elements.
    pub n2e: Csr,
    /// Per element: edge lengths of its target box along its axes u (0->1), v (0->3),
    /// w (0->4): the polycube lattice element under the map to the working frame.
    pub target: Vec<[f64; 3]>,
}

impl Work {
    /// Recompute the connectivity after a topology change.
    pub fn rebuild(&mut self) {
        let e = super::topology::edges(&self.mesh);
        self.nbr = super::topology::node_neighbours(self.mesh.nodes.len(), &e);
        self.n2e = super::topology::node_elements(&self.mesh);
        let quads: Vec<[u32; 4]> =
            super::topology::boundary_quads(&self.mesh).map(|b| b.into_iter().map(|q| q.nodes).collect()).unwrap_or_default();
        self.bgraph = boundary_graph(self.mesh.nodes.len(), &quads);
    }
}

/// A lattice mesh mapped onto the input (a level of the polycube map or a voxel
/// lattice): what the quality steps start from ([`super::quality::improve`]).
#[derive(Clone)]
pub struct Level {
    /// The lattice mesh (its elements and lattice bookkeeping).
    pub h: LatticeHex,
    /// Mapped node positions (working frame), their triangles, roles and curve neighbours.
    pub pos: Vec<[f64; 3]>,
    pub attach: Vec<u32>,
    pub role: Vec<Role>,
    pub curve_nb: Vec<Vec<u32>>,
    /// Boundary quads of the lattice mesh.
    pub bquads: Vec<[u32; 4]>,
    /// With the feature sheets, the feature corners (indices into the surface's
    /// feature corners) at which no node is held: the nodes there go onto one of
    /// their curves. Empty: a node at every corner the sheets reach.
    pub released_corners: Vec<u32>,
}

/// Per-node report of a stage.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct MoveStats {
    pub passes: usize,
    pub moves_tried: usize,
    pub moves_accepted: usize,
}

/// A scaled Jacobian with the degenerate value as -1.
#[inline]
pub fn q(v: f64) -> f64 {
    if v == DEGENERATE {
        -1.0
    } else {
        v
    }
}

/// Scaled Jacobian of element `e` with node `v` placed at `x`.
pub fn element_sj_with(m: &HexMesh, e: usize, v: u32, x: [f64; 3]) -> f64 {
    let el = m.elements[e];
    let p: [[f64; 3]; 8] = std::array::from_fn(|k| if el[k] == v { x } else { m.nodes[el[k] as usize] });
    q(scaled_jacobian(&p))
}

/// Smallest scaled Jacobian of the elements of node v with v at x, and how many of
/// them are inverted (scaled Jacobian <= 0).
pub fn local_eval(w: &Work, v: u32, x: [f64; 3]) -> (f64, usize) {
    let mut m = f64::INFINITY;
    let mut bad = 0;
    for &e in w.n2e.of(v as usize) {
        let s = element_sj_with(&w.mesh, e as usize, v, x);
        m = m.min(s);
        if s <= 0.0 {
            bad += 1;
        }
    }
    (m, bad)
}

/// Is `after` better than `before` (a larger minimum and no more inverted elements)?
#[inline]
pub fn better(after: (f64, usize), before: (f64, usize)) -> bool {
    after.0 > before.0 + 1e-9 && after.1 <= before.1
}

/// Mean length of the edges at node v.
pub fn mean_edge(w: &Work, v: usize) -> f64 {
    let nb = w.nbr.of(v);
    if nb.is_empty() {
        return 0.0;
    }
    nb.iter().map(|&u| norm(sub(w.mesh.nodes[u as usize], w.mesh.nodes[v]))).sum::<f64>() / nb.len() as f64
}

/// Flag node v and its edge neighbours (for the next pass of a Gauss-Seidel sweep).
pub fn mark_with_neighbours(w: &Work, v: usize, flags: &mut [bool]) {
    flags[v] = true;
    for &u in w.nbr.of(v) {
        flags[u as usize] = true;
    }
}

/// Mean length of the boundary edges of a mesh (0 without a boundary).
pub fn mean_boundary_edge(w: &Work) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in 0..w.mesh.nodes.len() {
        for &u in w.bgraph.of(v) {
            sum += norm(sub(w.mesh.nodes[u as usize], w.mesh.nodes[v]));
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// Area-weighted normals of the boundary quads at each node (zero for interior nodes).
pub fn quad_normals(n: usize, quads: &[[u32; 4]], pos: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut nn = vec![[0.0; 3]; n];
    for q in quads {
        let p = q.map(|i| pos[i as usize]);
        let nq = cross(sub(p[2], p[0]), sub(p[3], p[1]));
        for &v in q {
            nn[v as usize] = add(nn[v as usize], nq);
        }
    }
    for v in nn.iter_mut() {
        let l = norm(*v);
        if l > 0.0 {
            *v = scale(*v, 1.0 / l);
        }
    }
    nn
}

/// Boundary adjacency (edges of boundary quads).
pub fn boundary_graph(n: usize, quads: &[[u32; 4]]) -> Csr {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(quads.len() * 8);
    for q in quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            pairs.push((a, b));
            pairs.push((b, a));
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    Csr::from_pairs(n, pairs.into_iter())
}

/// Move a boundary node from `x` (on triangle `tri`) by the tangential part of `d`,
/// then back onto the surface / its curve. Returns the new position and triangle.
pub fn slide(sw: &Surface, role: Role, x: [f64; 3], tri: Attach, d: [f64; 3]) -> ([f64; 3], Attach) {
    match role {
        Role::Interior => (add(x, d), tri),
        Role::Corner(_) => (x, tri),
        Role::Curve(c) => {
            let cp = sw.closest_on_curve(c as usize, add(x, d));
            (cp.point, u32::MAX)
        }
        Role::Free => {
            let n = if tri != u32::MAX { sw.normal(tri) } else { sw.normal(sw.closest(x).1) };
            let dt = sub(d, scale(n, dot(d, n)));
            let (q, t, _) = sw.closest_facing(add(x, dt), n, 0.0);
            (q, t)
        }
    }
}

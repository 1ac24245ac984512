//! Level-0 construction of the spline from the control mesh, and its report.

use super::*;

impl Spline {
    /// Level-0 construction (no fitting, no refinement).
    pub fn construct(hex: &HexMesh, opts: &SplineOptions) -> Result<Spline> {
        let topo = Topology::new(hex, opts.sharp_angle_deg, &opts.sharp_edges)?;
        let ops: Vec<(Vec<u32>, SparseOp)> = {
            use rayon::prelude::*;
            (0..topo.ne as u32).into_par_iter().map(|e| construct::element_operator(&topo, e)).collect()
        };
        // compact vertex ids to basis ids (identity when every vertex is used)
        let mut used = vec![false; topo.nv];
        for (ids, _) in &ops {
            for &v in ids {
                used[v as usize] = true;
            }
        }
        let mut map = vec![u32::MAX; topo.nv];
        let mut kinds = Vec::new();
        let mut ctrl = Vec::new();
        for v in 0..topo.nv {
            if used[v] {
                map[v] = kinds.len() as u32;
                kinds.push(BasisKind::Vertex(v as u32));
                ctrl.push(hex.nodes[v]);
            }
        }
        let elems = ops
            .into_iter()
            .enumerate()
            .map(|(e, (ids, op))| Element {
                root: e as u32,
                level: 0,
                origin: [0, 0, 0],
                basis: ids.iter().map(|&v| map[v as usize]).collect(),
                op,
            })
            .collect();
        let mut sp = Spline {
            topo,
            root_nodes: hex.nodes.clone(),
            elems,
            ctrl,
            kinds,
            report: SplineReport::default(),
            opts: opts.clone(),
        };
        if opts.interpolate_vertices {
            sp.interpolate_vertices()?;
        }
        if opts.boundary_enrichment {
            refine::enrich_boundary(&mut sp);
            // on very thin meshes (fewer than 3 element layers) the truncated
            // vertex functions can become dependent; check when it is cheap
            if sp.ctrl.len() <= 4000 {
                let (rank, n) = check::independence_rank(&sp);
                if rank < n {
                    return Err(Error::SplineFailed(format!(
                        "boundary enrichment made the basis linearly dependent (rank {rank} of {n}); \
                         the mesh is too thin for it (use at least 3 element layers) or turn it off"
                    )));
                }
            }
        }
        if opts.repair_jacobian {
            sp.report.repaired_elements = refine::repair_jacobian(&mut sp);
        }
        sp.update_report();
        Ok(sp)
    }

    /// Solve for the vertex control points so that each control-mesh vertex is
    /// the spline's value at that vertex (level-0 spline, before enrichment).
    pub(super) fn interpolate_vertices(&mut self) -> Result<()> {
        use faer::linalg::solvers::Solve;
        use faer::sparse::{SparseColMat, Triplet};
        let n = self.ctrl.len();
        let mut row_of = vec![u32::MAX; n];
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut rhs = faer::Mat::<f64>::zeros(n, 3);
        for el in &self.elems {
            let corners = self.topo.elements[el.root as usize];
            for (c, &v) in corners.iter().enumerate() {
                // basis id of vertex v
                let Some(bi) = el.basis.iter().position(|&b| self.kinds[b as usize] == BasisKind::Vertex(v)) else {
                    continue;
                };
                let row = el.basis[bi] as usize;
                if row_of[row] != u32::MAX {
                    continue;
                }
                row_of[row] = 1;
                let bits = topology::BITS_OF_VTK[c];
                let k = bernstein::bidx(3 * bits[0], 3 * bits[1], 3 * bits[2]);
                for r in 0..el.op.rows() {
                    let (cols, vals) = el.op.row(r);
                    if let Some(p) = cols.iter().position(|&x| x as usize == k) {
                        trip.push(Triplet::new(row, el.basis[r] as usize, vals[p]));
                    }
                }
                let x = self.root_nodes[v as usize];
                for j in 0..3 {
                    rhs[(row, j)] = x[j];
                }
            }
        }
        if row_of.iter().any(|&r| r == u32::MAX) {
            return Err(Error::SplineFailed("interpolation: a vertex function has no corner".into()));
        }
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip)
            .map_err(|e| Error::SplineFailed(format!("interpolation matrix: {e:?}")))?;
        let lu = a.sp_lu().map_err(|e| Error::SplineFailed(format!("interpolation factorisation: {e:?}")))?;
        lu.solve_in_place(rhs.as_mut());
        let mut pts = Vec::with_capacity(n);
        for i in 0..n {
            let p = [rhs[(i, 0)], rhs[(i, 1)], rhs[(i, 2)]];
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::SplineFailed("interpolation produced non-finite control points".into()));
            }
            pts.push(p);
        }
        self.ctrl = pts;
        Ok(())
    }

    /// Recompute the counts and the Gauss-point Jacobian measures of the report.
    pub fn update_report(&mut self) {
        let q = check::gauss_jacobians(self, 3);
        let r = &mut self.report;
        r.elements = self.elems.len();
        r.basis_functions = self.ctrl.len();
        r.control_mesh_vertices = self.topo.nv;
        r.control_mesh_elements = self.topo.ne;
        r.max_level = self.elems.iter().map(|e| e.level).max().unwrap_or(0);
        r.extraordinary_edges = self.topo.extraordinary_edge_count();
        r.sharp_edges = self.topo.sharp_edge_count();
        r.boundary_faces = self.topo.bquads.len();
        r.bernstein_functions = self.kinds.iter().filter(|k| matches!(k, BasisKind::Bernstein { .. })).count();
        r.operator_nonzeros = self.elems.iter().map(|e| e.op.nnz()).sum();
        r.min_jacobian = q.min_det;
        r.min_scaled_jacobian = q.min_scaled;
        r.mean_scaled_jacobian = q.mean_scaled;
        r.negative_jacobian_elements = q.negative_elements;
    }

    /// The C2 share of the interior faces ([`SplineReport::c2_faces`]).
    pub fn update_continuity(&mut self) {
        let c = check::continuity(self, 2, None);
        let faces = c.regular.faces + c.other.faces;
        let c2 = faces - c.regular.faces_c2_broken - c.other.faces_c2_broken;
        self.report.interior_faces = faces;
        self.report.c2_faces = c2;
        self.report.c2_face_share = if faces > 0 { c2 as f64 / faces as f64 } else { 0.0 };
    }

    /// Remove basis functions that vanish everywhere and renumber.
    pub(super) fn compact(&mut self) {
        let mut used = vec![false; self.ctrl.len()];
        for el in &self.elems {
            for &b in &el.basis {
                used[b as usize] = true;
            }
        }
        if used.iter().all(|&u| u) {
            return;
        }
        let mut map = vec![u32::MAX; used.len()];
        let mut ctrl = Vec::new();
        let mut kinds = Vec::new();
        for i in 0..used.len() {
            if used[i] {
                map[i] = ctrl.len() as u32;
                ctrl.push(self.ctrl[i]);
                kinds.push(self.kinds[i]);
            }
        }
        for el in &mut self.elems {
            for b in &mut el.basis {
                *b = map[*b as usize];
            }
        }
        self.ctrl = ctrl;
        self.kinds = kinds;
    }
}

//! The spline's accessors and its evaluation: elements, extraction operators,
//! Bézier points, the map and its Jacobian, basis values and gradients.

use super::*;

impl Spline {
    pub fn num_elements(&self) -> usize {
        self.elems.len()
    }

    pub fn num_basis(&self) -> usize {
        self.ctrl.len()
    }

    /// Control points (one per basis function).
    pub fn control_points(&self) -> &[[f64; 3]] {
        &self.ctrl
    }

    /// Replace the control points (same count); the report is not updated.
    pub fn set_control_points(&mut self, pts: Vec<[f64; 3]>) -> Result<()> {
        if pts.len() != self.ctrl.len() {
            return Err(Error::InvalidArgument(format!(
                "expected {} control points, got {}",
                self.ctrl.len(),
                pts.len()
            )));
        }
        if pts.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(Error::InvalidArgument("non-finite control point".into()));
        }
        self.ctrl = pts;
        Ok(())
    }

    /// Weights of the control points (all 1: the spline is polynomial).
    pub fn weights(&self) -> Vec<f64> {
        vec![1.0; self.ctrl.len()]
    }

    pub fn basis_kind(&self, i: usize) -> BasisKind {
        self.kinds[i]
    }

    pub fn elements(&self) -> &[Element] {
        &self.elems
    }

    pub fn element(&self, e: usize) -> Result<&Element> {
        self.elems.get(e).ok_or_else(|| {
            Error::InvalidArgument(format!("element {e} out of range (the spline has {})", self.elems.len()))
        })
    }

    /// Global basis ids of element e (rows of its extraction operator).
    pub fn element_basis(&self, e: usize) -> Result<&[u32]> {
        Ok(&self.element(e)?.basis)
    }

    /// Extraction operator of element e, dense, row-major `n x 64`.
    pub fn extraction_operator(&self, e: usize) -> Result<Vec<f64>> {
        Ok(self.element(e)?.op.to_dense())
    }

    /// Sparse extraction operator of element e.
    pub fn extraction_operator_sparse(&self, e: usize) -> Result<&SparseOp> {
        Ok(&self.element(e)?.op)
    }

    /// The 64 Bézier control points of element e: Pb[k] = sum_r C[r][k] P[ids[r]].
    pub fn bezier_points(&self, e: usize) -> Result<Vec<[f64; 3]>> {
        let el = self.element(e)?;
        Ok(self.bezier_points_of(el))
    }

    pub(super) fn bezier_points_of(&self, el: &Element) -> Vec<[f64; 3]> {
        let mut pb = vec![[0.0; 3]; NB];
        for r in 0..el.op.rows() {
            let p = self.ctrl[el.basis[r] as usize];
            let (c, v) = el.op.row(r);
            for (&k, &x) in c.iter().zip(v) {
                let q = &mut pb[k as usize];
                q[0] += x * p[0];
                q[1] += x * p[1];
                q[2] += x * p[2];
            }
        }
        pb
    }

    pub(super) fn check_uvw(e: usize, u: f64, v: f64, w: f64) -> Result<()> {
        for (n, x) in [("u", u), ("v", v), ("w", w)] {
            if !(x.is_finite() && (-1e-12..=1.0 + 1e-12).contains(&x)) {
                return Err(Error::InvalidArgument(format!(
                    "parameter {n} = {x} of element {e} is outside [0, 1]"
                )));
            }
        }
        Ok(())
    }

    /// The spline map and its Jacobian at (u, v, w) in [0,1]^3 of element e.
    /// `jac[i][j] = d x_i / d xi_j` (xi = (u, v, w) of the element).
    pub fn evaluate(&self, e: usize, u: f64, v: f64, w: f64) -> Result<([f64; 3], [[f64; 3]; 3])> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let pb = self.bezier_points_of(el);
        Ok(map_from_bezier(&pb, [u, v, w]))
    }

    /// Values of the element's basis functions at (u, v, w): (ids, values).
    pub fn basis_values(&self, e: usize, u: f64, v: f64, w: f64) -> Result<(Vec<u32>, Vec<f64>)> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let b = bernstein::values([u, v, w]);
        Ok((el.basis.clone(), apply_rows(&el.op, &b)))
    }

    /// Values and parametric gradients (d/du, d/dv, d/dw) of the element's basis
    /// functions at (u, v, w).
    pub fn basis_gradients(&self, e: usize, u: f64, v: f64, w: f64) -> Result<(Vec<u32>, Vec<f64>, Vec<[f64; 3]>)> {
        Self::check_uvw(e, u, v, w)?;
        let el = self.element(e)?;
        let (b, g) = bernstein::values_and_gradients([u, v, w]);
        let vals = apply_rows(&el.op, &b);
        let mut grads = vec![[0.0; 3]; el.op.rows()];
        for (r, gr) in grads.iter_mut().enumerate() {
            let (c, v) = el.op.row(r);
            for (&k, &x) in c.iter().zip(v) {
                for d in 0..3 {
                    gr[d] += x * g[k as usize][d];
                }
            }
        }
        Ok((el.basis.clone(), vals, grads))
    }

    pub fn report(&self) -> &SplineReport {
        &self.report
    }

    pub fn options(&self) -> &SplineOptions {
        &self.opts
    }

    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// Control-mesh node positions as given.
    pub fn control_mesh_nodes(&self) -> &[[f64; 3]] {
        &self.root_nodes
    }

    /// The control mesh with the current control points of its vertex functions
    /// (vertices whose function was truncated away keep their input position).
    pub fn control_mesh(&self) -> HexMesh {
        let mut nodes = self.root_nodes.clone();
        for (i, k) in self.kinds.iter().enumerate() {
            if let BasisKind::Vertex(v) = k {
                nodes[*v as usize] = self.ctrl[i];
            }
        }
        HexMesh { nodes, elements: self.topo.elements.clone() }
    }

    /// Leaf element e as (root element, lower corner, upper corner) in the root's
    /// parameters.
    pub fn element_box(&self, e: usize) -> Result<(u32, [f64; 3], [f64; 3])> {
        let el = self.element(e)?;
        let h = 1.0 / (1u32 << el.level) as f64;
        let lo = el.origin.map(|o| o as f64 * h);
        Ok((el.root, lo, lo.map(|x| x + h)))
    }

    /// Position in root grid units of Bézier node n of element e (used by tests).
    pub fn node_key(&self, e: usize, n: usize) -> Result<NodeKey> {
        let el = self.element(e)?;
        if n >= NB {
            return Err(Error::InvalidArgument(format!("Bézier node {n} out of range")));
        }
        Ok(nodes::key_of(&self.topo, el.root, el.node_pos(n)))
    }
}

/// Rows of `op` applied to a vector of 64 Bernstein values.
pub(crate) fn apply_rows(op: &SparseOp, b: &[f64; NB]) -> Vec<f64> {
    (0..op.rows())
        .map(|r| {
            let (c, v) = op.row(r);
            c.iter().zip(v).map(|(&k, &x)| x * b[k as usize]).sum()
        })
        .collect()
}

/// Point and Jacobian of a tricubic Bézier volume at p.
pub fn map_from_bezier(pb: &[[f64; 3]], p: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let (b, g) = bernstein::values_and_gradients(p);
    let mut x = [0.0; 3];
    let mut j = [[0.0; 3]; 3];
    for k in 0..NB {
        for i in 0..3 {
            x[i] += b[k] * pb[k][i];
            for d in 0..3 {
                j[i][d] += g[k][d] * pb[k][i];
            }
        }
    }
    (x, j)
}

/// Determinant of a 3x3 matrix.
pub fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1]) - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// det J / product of the column lengths (1 for an orthogonal frame).
pub fn scaled_det(j: &[[f64; 3]; 3]) -> f64 {
    let col = |d: usize| (j[0][d] * j[0][d] + j[1][d] * j[1][d] + j[2][d] * j[2][d]).sqrt();
    let l = col(0) * col(1) * col(2);
    if l <= f64::MIN_POSITIVE {
        return -1.0;
    }
    det3(j) / l
}

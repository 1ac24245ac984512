//! A small software rasteriser for pictures in reports: triangle meshes (flat
//! two-sided Lambert shading, z-buffer, optional edge overlay) and point clouds,
//! orthographic camera, PNG out (image crate).

use crate::error::{Error, Result};
use std::path::Path;

/// Where the camera looks from (degrees): azimuth about +z from +x, elevation above
/// the xy plane. The view direction points at the centre of all layers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub azimuth: f64,
    pub elevation: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera { azimuth: -55.0, elevation: 28.0 }
    }
}

/// What to draw.
pub enum Layer<'a> {
    /// Triangles (vertex positions + index triples) in one colour, with optional edges
    /// (vertex index pairs) drawn dark on top.
    Surface { vertices: &'a [[f64; 3]], triangles: &'a [[u32; 3]], edges: &'a [[u32; 2]], colour: [u8; 3] },
    /// Points as small discs, each with its colour.
    Points { points: &'a [[f64; 3]], colours: &'a [[u8; 3]], radius_px: f64 },
}

struct View {
    right: [f64; 3],
    up: [f64; 3],
    fwd: [f64; 3],
    centre: [f64; 3],
    scale: f64,
    w: usize,
    h: usize,
}

impl View {
    /// Screen x, y (pixels) and depth (larger = nearer).
    fn project(&self, p: [f64; 3]) -> [f64; 3] {
        let d = [p[0] - self.centre[0], p[1] - self.centre[1], p[2] - self.centre[2]];
        let dot = |a: [f64; 3]| a[0] * d[0] + a[1] * d[1] + a[2] * d[2];
        [self.w as f64 * 0.5 + self.scale * dot(self.right), self.h as f64 * 0.5 - self.scale * dot(self.up), -dot(self.fwd)]
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm(a: [f64; 3]) -> [f64; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if l > 0.0 {
        a.map(|v| v / l)
    } else {
        a
    }
}

/// An RGB image with a depth buffer.
pub struct Canvas {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[u8; 3]>,
    depth: Vec<f64>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        Canvas { width: w, height: h, rgb: vec![[255, 255, 255]; w * h], depth: vec![f64::NEG_INFINITY; w * h] }
    }

    fn put(&mut self, x: i64, y: i64, z: f64, c: [u8; 3]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = y as usize * self.width + x as usize;
        if z >= self.depth[i] {
            self.depth[i] = z;
            self.rgb[i] = c;
        }
    }

    fn triangle(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3], col: [u8; 3]) {
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area.abs() < 1e-12 {
            return;
        }
        let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as i64;
        let x1 = a[0].max(b[0]).max(c[0]).ceil().min(self.width as f64 - 1.0) as i64;
        let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as i64;
        let y1 = a[1].max(b[1]).max(c[1]).ceil().min(self.height as f64 - 1.0) as i64;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let w0 = ((b[0] - px) * (c[1] - py) - (b[1] - py) * (c[0] - px)) / area;
                let w1 = ((c[0] - px) * (a[1] - py) - (c[1] - py) * (a[0] - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 >= -1e-9 && w1 >= -1e-9 && w2 >= -1e-9 {
                    self.put(x, y, w0 * a[2] + w1 * b[2] + w2 * c[2], col);
                }
            }
        }
    }

    fn line(&mut self, a: [f64; 3], b: [f64; 3], bias: f64, col: [u8; 3]) {
        let n = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 100_000);
        for s in 0..=n {
            let t = s as f64 / n as f64;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
            self.put(p[0].round() as i64, p[1].round() as i64, p[2] + bias, col);
        }
    }

    fn disc(&mut self, p: [f64; 3], r: f64, col: [u8; 3]) {
        let ri = r.ceil() as i64;
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                if ((dx * dx + dy * dy) as f64) <= r * r {
                    self.put(p[0].round() as i64 + dx, p[1].round() as i64 + dy, p[2], col);
                }
            }
        }
    }

    pub fn save_png(&self, path: &Path) -> Result<()> {
        let buf: Vec<u8> = self.rgb.iter().flatten().copied().collect();
        image::save_buffer(path, &buf, self.width as u32, self.height as u32, image::ColorType::Rgb8)
            .map_err(|e| Error::io(path.display(), e))
    }
}

/// Draw the layers into a `width` x `height` canvas, framed to fit all of them.
pub fn render(layers: &[Layer], width: usize, height: usize, cam: Camera) -> Result<Canvas> {
    if width == 0 || height == 0 || width * height > 64_000_000 {
        return Err(Error::InvalidArgument(format!("image size {width} x {height} out of range")));
    }
    let (az, el) = (cam.azimuth.to_radians(), cam.elevation.to_radians());
    // direction from the scene towards the camera
    let to_cam = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
    let fwd = to_cam.map(|v| -v);
    let right = norm(cross(fwd, [0.0, 0.0, 1.0]));
    let up = cross(right, fwd);
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |p: &[f64; 3]| {
        for a in 0..3 {
            if p[a].is_finite() {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
    };
    for l in layers {
        match l {
            Layer::Surface { vertices, .. } => vertices.iter().for_each(&mut grow),
            Layer::Points { points, .. } => points.iter().for_each(&mut grow),
        }
    }
    if !lo[0].is_finite() {
        return Err(Error::InvalidArgument("nothing to render".into()));
    }
    let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    let mut view = View { right, up, fwd, centre, scale: 1.0, w: width, h: height };
    // fit the projected bounding box corners with a margin
    let (mut ex, mut ey) = (1e-12f64, 1e-12f64);
    for c in 0..8 {
        let p = [if c & 1 == 0 { lo[0] } else { hi[0] }, if c & 2 == 0 { lo[1] } else { hi[1] }, if c & 4 == 0 { lo[2] } else { hi[2] }];
        let q = view.project(p);
        ex = ex.max((q[0] - width as f64 * 0.5).abs());
        ey = ey.max((q[1] - height as f64 * 0.5).abs());
    }
    view.scale = 0.92 * (width as f64 * 0.5 / ex).min(height as f64 * 0.5 / ey);
    let diag = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
    let mut cv = Canvas::new(width, height);
    let light = norm([to_cam[0] + 0.3 * up[0] - 0.3 * right[0], to_cam[1] + 0.3 * up[1] - 0.3 * right[1], to_cam[2] + 0.3 * up[2] - 0.3 * right[2]]);
    for l in layers {
        match l {
            Layer::Surface { vertices, triangles, edges, colour } => {
                let proj: Vec<[f64; 3]> = vertices.iter().map(|&p| view.project(p)).collect();
                for t in triangles.iter() {
                    if t.iter().any(|&i| i as usize >= vertices.len()) {
                        continue;
                    }
                    let [a, b, c] = t.map(|i| vertices[i as usize]);
                    let n = norm(cross([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]));
                    let lam = (n[0] * light[0] + n[1] * light[1] + n[2] * light[2]).abs();
                    let s = 0.35 + 0.65 * lam;
                    let col = colour.map(|v| (v as f64 * s).round().clamp(0.0, 255.0) as u8);
                    let [pa, pb, pc] = t.map(|i| proj[i as usize]);
                    cv.triangle(pa, pb, pc, col);
                }
                for e in edges.iter() {
                    if e.iter().any(|&i| i as usize >= vertices.len()) {
                        continue;
                    }
                    cv.line(proj[e[0] as usize], proj[e[1] as usize], 2e-3 * diag, [40, 40, 40]);
                }
            }
            Layer::Points { points, colours, radius_px } => {
                for (i, &p) in points.iter().enumerate() {
                    let c = colours.get(i).copied().or(colours.last().copied()).unwrap_or([40, 80, 160]);
                    cv.disc(view.project(p), *radius_px, c);
                }
            }
        }
    }
    Ok(cv)
}

/// Render and write a PNG.
pub fn render_png(path: &Path, layers: &[Layer], width: usize, height: usize, cam: Camera) -> Result<()> {
    render(layers, width, height, cam)?.save_png(path)
}

/// The boundary quads of a hex mesh (faces used by one element), as triangles and
/// edges for a [`Layer::Surface`].
pub fn hex_boundary(elements: &[[u32; 8]]) -> (Vec<[u32; 3]>, Vec<[u32; 2]>) {
    const F: [[usize; 4]; 6] = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]];
    let mut count = std::collections::HashMap::new();
    for e in elements {
        for f in F {
            let q = f.map(|i| e[i]);
            let mut k = q;
            k.sort_unstable();
            count.entry(k).or_insert((0usize, q)).0 += 1;
        }
    }
    let mut tris = Vec::new();
    let mut edges = std::collections::BTreeSet::new();
    for (_, (n, q)) in count {
        if n == 1 {
            tris.push([q[0], q[1], q[2]]);
            tris.push([q[0], q[2], q[3]]);
            for i in 0..4 {
                let (a, b) = (q[i], q[(i + 1) % 4]);
                edges.insert([a.min(b), a.max(b)]);
            }
        }
    }
    (tris, edges.into_iter().collect())
}

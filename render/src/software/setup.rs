//! Triangle setup for the CPU rasterisers: a scene's triangles transformed to clip space,
//! clipped to the depth range, culled, and set up in sample space ([`Setup`]: corners,
//! edge functions' scale, attributes divided by `w`, bounds and mip levels).

use glam::{Mat4, Vec3, Vec4};

use super::sampling::{Levels, Trilinear};
use super::shading::Shading;
use super::textures::SoftwareTextures;
use crate::scene::{DrawMaterial, DrawMesh, DrawScene};

/// One triangle ready to rasterise: sample-space vertices, attributes divided by `w`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Setup {
    /// The corners' x in samples (left to right), ordered so that the area is positive.
    pub(crate) x: [f32; 3],
    /// The corners' y in samples (top to bottom).
    pub(crate) y: [f32; 3],
    /// Depth (NDC z), interpolated linearly on screen.
    pub(crate) z: [f32; 3],
    /// `1 / w`.
    pub(crate) q: [f32; 3],
    /// Texture coordinates divided by `w`.
    pub(crate) uq: [[f32; 2]; 3],
    /// `1 / (twice the signed area)`, positive (vertices ordered so that it is).
    pub(crate) inv_area: f32,
    /// The mesh's material (an index into the scene's).
    pub(crate) material: u32,
    /// The mesh has normals: colour renders light it.
    pub(crate) lit: bool,
    /// A back face (drawn double-sided): its normal is flipped to face the viewer.
    pub(crate) back: bool,
    /// The material texture's two mip levels and the second's weight, chosen at the centroid.
    pub(crate) lod: Trilinear,
    /// Inclusive sample bounds: the first sample column and row the triangle may cover.
    pub(crate) min: [i32; 2],
    /// The last sample column and row it may cover (inclusive).
    pub(crate) max: [i32; 2],
}

/// A vertex in clip space with its attributes, for near/far clipping.
#[derive(Clone, Copy, Debug)]
struct ClipVertex {
    /// Position in clip space.
    clip: Vec4,
    /// Texture coordinates.
    uv: [f32; 2],
    /// Normal (zero for unlit meshes).
    normal: Vec3,
    /// Tangent, w the bitangent's sign (zero without tangents).
    tangent: Vec4,
}

impl ClipVertex {
    /// The vertex a fraction `t` of the way from `a` to `b`, every attribute interpolated.
    fn lerp(a: &ClipVertex, b: &ClipVertex, t: f32) -> ClipVertex {
        ClipVertex {
            clip: a.clip + (b.clip - a.clip) * t,
            uv: [
                a.uv[0] + (b.uv[0] - a.uv[0]) * t,
                a.uv[1] + (b.uv[1] - a.uv[1]) * t,
            ],
            normal: a.normal + (b.normal - a.normal) * t,
            tangent: a.tangent + (b.tangent - a.tangent) * t,
        }
    }
}

/// Transforms, clips (near and far planes), culls and sets up every triangle of `scene`, in
/// draw order, for a target of `sw`×`sh` samples, with their shading when the textures were
/// prepared with colour.
pub(crate) fn setup(
    scene: &DrawScene,
    textures: &SoftwareTextures,
    view_proj: Mat4,
    sw: f32,
    sh: f32,
) -> (Vec<Setup>, Vec<Shading>) {
    let mut set_up = SetUpMeshes::default();
    set_up.set_up(
        &scene.meshes,
        &scene.materials,
        textures,
        view_proj,
        [sw, sh],
    );
    (set_up.triangles, set_up.shading)
}

/// Triangles set up by [`SetUpMeshes::set_up`], its buffers reused from call to call.
#[derive(Debug, Default)]
pub(crate) struct SetUpMeshes {
    /// The triangles set up, in draw order.
    pub(crate) triangles: Vec<Setup>,
    /// Per triangle, its shading (when the textures were prepared with colour).
    pub(crate) shading: Vec<Shading>,
    /// A mesh's positions in clip space.
    clip: Vec<Vec4>,
}

impl SetUpMeshes {
    /// [`setup`] of `meshes` (of `materials`) alone, replacing what was set up before.
    pub(crate) fn set_up(
        &mut self,
        meshes: &[DrawMesh],
        materials: &[DrawMaterial],
        textures: &SoftwareTextures,
        view_proj: Mat4,
        size: [f32; 2],
    ) {
        // Reserved up front: growing it (tens of megabytes for a large tree) was a tenth of a
        // small render's time.
        let count = meshes.iter().map(|m| m.indices.len() / 3).sum();
        self.triangles.clear();
        self.triangles.reserve(count);
        self.shading.clear();
        self.shading
            .reserve(if textures.colour { count } else { 0 });
        for mesh in meshes {
            self.set_up_mesh(mesh, &materials[mesh.material], textures, view_proj, size);
        }
    }

    /// One mesh of [`SetUpMeshes::set_up`], drawn with `material`: its triangles and their
    /// shading appended.
    fn set_up_mesh(
        &mut self,
        mesh: &DrawMesh,
        material: &DrawMaterial,
        textures: &SoftwareTextures,
        view_proj: Mat4,
        [sw, sh]: [f32; 2],
    ) {
        let SetUpMeshes {
            triangles: out,
            shading,
            clip,
        } = self;
        let shade = textures.colour;
        clip.clear();
        clip.extend((mesh.positions.iter()).map(|p| view_proj * Vec3::from(*p).extend(1.0)));
        let texture = material.texture.map(|t| &textures.textures[t]);
        let lit = mesh.normals.is_some();
        // The normal map applies to lit meshes with tangents when it was prepared (colour).
        let normal_map = match (lit, &mesh.tangents, material.normal_texture) {
            (true, Some(_), Some(t)) => Some(&textures.normal_maps[t]).filter(|l| !l.0.is_empty()),
            _ => None,
        };
        for tri in mesh.indices.chunks_exact(3) {
            let vertex = |k: usize| {
                let i = tri[k] as usize;
                ClipVertex {
                    clip: clip[i],
                    uv: mesh.uvs.as_ref().map_or([0.0; 2], |u| u[i]),
                    normal: mesh
                        .normals
                        .as_ref()
                        .map_or(Vec3::ZERO, |n| Vec3::from(n[i])),
                    tangent: mesh
                        .tangents
                        .as_ref()
                        .map_or(Vec4::ZERO, |t| Vec4::from(t[i])),
                }
            };
            let corners = [vertex(0), vertex(1), vertex(2)];
            let inside = |v: &ClipVertex| v.clip.z >= 0.0 && v.clip.z <= v.clip.w;
            let mut push = |c: [&ClipVertex; 3]| {
                if let Some((mut s, sh)) =
                    setup_triangle(c, material, [texture, normal_map], [lit, shade], sw, sh)
                {
                    s.material = mesh.material as u32;
                    out.push(s);
                    if shade {
                        shading.push(sh);
                    }
                }
            };
            if corners.iter().all(inside) {
                push([&corners[0], &corners[1], &corners[2]]);
                continue;
            }
            let polygon = clip_polygon(corners.to_vec());
            for k in 1..polygon.len().saturating_sub(1) {
                push([&polygon[0], &polygon[k], &polygon[k + 1]]);
            }
        }
    }
}

/// `polygon` clipped to `0 ≤ z ≤ w` (wgpu's depth range), Sutherland–Hodgman.
fn clip_polygon(polygon: Vec<ClipVertex>) -> Vec<ClipVertex> {
    let near = |v: &ClipVertex| v.clip.z;
    let far = |v: &ClipVertex| v.clip.w - v.clip.z;
    let mut p = polygon;
    for plane in [&near as &dyn Fn(&ClipVertex) -> f32, &far] {
        if p.iter().all(|v| plane(v) >= 0.0) {
            continue;
        }
        let mut next = Vec::with_capacity(p.len() + 1);
        for i in 0..p.len() {
            let (a, b) = (&p[i], &p[(i + 1) % p.len()]);
            let (da, db) = (plane(a), plane(b));
            if da >= 0.0 {
                next.push(*a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                next.push(ClipVertex::lerp(a, b, da / (da - db)));
            }
        }
        p = next;
    }
    p
}

/// One clipped triangle in sample space, or `None` when it is culled, degenerate or off the
/// image.
fn setup_triangle(
    corners: [&ClipVertex; 3],
    material: &DrawMaterial,
    [texture, normal_map]: [Option<&Levels>; 2],
    [lit, shade]: [bool; 2],
    sw: f32,
    sh: f32,
) -> Option<(Setup, Shading)> {
    let mut v = corners.map(|c| {
        let q = 1.0 / c.clip.w;
        (
            (c.clip.x * q * 0.5 + 0.5) * sw,
            (0.5 - c.clip.y * q * 0.5) * sh,
            c.clip.z * q,
            q,
            [c.uv[0] * q, c.uv[1] * q],
            c,
        )
    });
    if v.iter()
        .any(|c| !(c.0.is_finite() && c.1.is_finite() && c.3 > 0.0))
    {
        return None;
    }
    // Twice the signed area in sample space (y down): negative for counter-clockwise (front)
    // faces of wgpu's y-up clip space.
    let area = (v[1].0 - v[0].0) * (v[2].1 - v[0].1) - (v[2].0 - v[0].0) * (v[1].1 - v[0].1);
    if area == 0.0 || !area.is_finite() || (area > 0.0 && !material.double_sided) {
        return None;
    }
    // Positive: clockwise on screen, a back face (kept only when double-sided).
    let back = area > 0.0;
    if area < 0.0 {
        v.swap(1, 2);
    }
    let area = area.abs();
    let min_x = v.iter().map(|c| c.0).fold(f32::INFINITY, f32::min);
    let max_x = v.iter().map(|c| c.0).fold(f32::NEG_INFINITY, f32::max);
    let min_y = v.iter().map(|c| c.1).fold(f32::INFINITY, f32::min);
    let max_y = v.iter().map(|c| c.1).fold(f32::NEG_INFINITY, f32::max);
    // Samples at centres: sample i is at i + 0.5.
    let min = [(min_x - 0.5).ceil().max(0.0), (min_y - 0.5).ceil().max(0.0)];
    let max = [
        (max_x - 0.5).floor().min(sw - 1.0),
        (max_y - 0.5).floor().min(sh - 1.0),
    ];
    if min[0] > max[0] || min[1] > max[1] {
        return None;
    }
    let mut s = Setup {
        x: v.map(|c| c.0),
        y: v.map(|c| c.1),
        z: v.map(|c| c.2),
        q: v.map(|c| c.3),
        uq: v.map(|c| c.4),
        inv_area: 1.0 / area,
        material: 0,
        lit,
        back,
        lod: Trilinear::default(),
        min: [min[0] as i32, min[1] as i32],
        max: [max[0] as i32, max[1] as i32],
    };
    // Colour renders' (and the bake's) levels now; a coverage render's when a band first
    // tests a sample of the triangle ([`Raster::with_lod`]): inside a crown most triangles
    // are drawn over samples covered already, and never need it.
    if shade && let Some(levels) = texture {
        s.lod = levels.pair(centroid_lod(&s, levels));
    }
    let mut shading = Shading::default();
    if shade {
        // In the vertices' final order (swapped to make the area positive).
        shading.nq = v.map(|c| c.5.normal * c.3);
        shading.tq = normal_map.map(|_| {
            v.map(|c| {
                c.5.tangent.truncate().extend(0.0) * c.3 + Vec4::new(0.0, 0.0, 0.0, c.5.tangent.w)
            })
        });
        if let Some(levels) = normal_map {
            shading.normal_lod = levels.pair(centroid_lod(&s, levels));
        }
    }
    Some((s, shading))
}

impl Setup {
    /// Screen-space barycentric weights of point `(px, py)`: the three edge functions, each
    /// scaled by `1 / (twice the area)`.
    #[inline]
    pub(crate) fn weights(&self, px: f32, py: f32) -> [f32; 3] {
        let e = |a: usize, b: usize| {
            (self.x[b] - self.x[a]) * (py - self.y[a]) - (self.y[b] - self.y[a]) * (px - self.x[a])
        };
        [
            e(1, 2) * self.inv_area,
            e(2, 0) * self.inv_area,
            e(0, 1) * self.inv_area,
        ]
    }

    /// Perspective-correct texture coordinates at weights `b`, and `Σ b·q`.
    #[inline]
    pub(crate) fn uv(&self, b: [f32; 3]) -> ([f32; 2], f32) {
        let q = b[0] * self.q[0] + b[1] * self.q[1] + b[2] * self.q[2];
        let u = b[0] * self.uq[0][0] + b[1] * self.uq[1][0] + b[2] * self.uq[2][0];
        let v = b[0] * self.uq[0][1] + b[1] * self.uq[1][1] + b[2] * self.uq[2][1];
        ([u / q, v / q], q)
    }

    /// The texture coordinates at the corners where `1/w` is the same at all three (an affine
    /// triangle, as every one an orthographic view draws): then the coordinates at weights `b`
    /// are `Σ b·uv` ([`affine_uv`]), with no division per sample.
    #[inline]
    pub(crate) fn affine_corners(&self) -> Option<[[f32; 2]; 3]> {
        let q = self.q;
        (q[0] == q[1] && q[1] == q[2]).then(|| self.uq.map(|c| [c[0] / q[0], c[1] / q[0]]))
    }
}

/// The texture coordinates at weights `b` of an affine triangle whose corners have `uv`
/// ([`Setup::affine_corners`]): `Σ b·uv` left to right, as the eight-sample lanes sum them.
#[inline]
pub(crate) fn affine_uv(uv: &[[f32; 2]; 3], b: [f32; 3]) -> [f32; 2] {
    [0, 1].map(|k| b[0] * uv[0][k] + b[1] * uv[1][k] + b[2] * uv[2][k])
}

/// The mip level of `levels` at `s`'s centroid: log2 of the longer of the texture
/// coordinates' screen derivatives along x and y, in level-0 texels (as a GPU's trilinear
/// filter), at least 0.
pub(super) fn centroid_lod(s: &Setup, levels: &Levels) -> f32 {
    let (w, h) = (levels.0[0].0 as f32, levels.0[0].1 as f32);
    let cx = (s.x[0] + s.x[1] + s.x[2]) / 3.0;
    let cy = (s.y[0] + s.y[1] + s.y[2]) / 3.0;
    let (uv, _) = s.uv(s.weights(cx, cy));
    let (ux, _) = s.uv(s.weights(cx + 1.0, cy));
    let (uy, _) = s.uv(s.weights(cx, cy + 1.0));
    let dx = hypot((ux[0] - uv[0]) * w, (ux[1] - uv[1]) * h);
    let dy = hypot((uy[0] - uv[0]) * w, (uy[1] - uv[1]) * h);
    let rho = dx.max(dy);
    if rho.is_finite() && rho > 1.0 {
        rho.log2()
    } else {
        0.0
    }
}

/// `√(x² + y²)` as glibc's `hypotf` computes it (the squares exact in `f64`, their sum and
/// its root rounded there, then to `f32`; infinite when either argument is, even beside a
/// NaN): the same bits, without the library call (which the mip level of every triangle of
/// every render needs), and the same on every platform, whatever its C library.
#[inline]
fn hypot(x: f32, y: f32) -> f32 {
    if x.is_infinite() || y.is_infinite() {
        return f32::INFINITY;
    }
    let (x, y) = (f64::from(x), f64::from(y));
    (x * x + y * y).sqrt() as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An affine triangle's texture coordinates summed without a division are the divided
    /// ones but for rounding; a perspective triangle has no affine corners.
    #[test]
    fn affine_texture_coordinates_are_the_divided_ones() {
        let setup = |q: [f32; 3]| Setup {
            x: [1.0, 9.0, 3.0],
            y: [2.0, 4.0, 11.0],
            z: [0.0; 3],
            q,
            uq: [[0.1, 0.9], [0.7, 0.2], [0.4, 0.5]].map(|[u, v]| [u * q[0], v * q[0]]),
            inv_area: 1.0 / 68.0,
            material: 0,
            lit: false,
            back: false,
            lod: Trilinear::default(),
            min: [1, 2],
            max: [8, 10],
        };
        let t = setup([0.5; 3]);
        let corners = t.affine_corners().expect("affine");
        assert_eq!(corners[1], [0.7, 0.2]);
        for (px, py) in [(2.5, 3.5), (4.5, 6.5), (3.0, 9.0), (7.5, 4.5)] {
            let b = t.weights(px, py);
            let (divided, _) = t.uv(b);
            let summed = affine_uv(&corners, b);
            for k in 0..2 {
                assert!(
                    (divided[k] - summed[k]).abs() < 1e-6,
                    "{divided:?} {summed:?}"
                );
            }
        }
        assert!(setup([0.5, 0.25, 0.5]).affine_corners().is_none());
    }

    /// The mip level's `hypot` gives glibc's `hypotf` bits (what the renders read before it
    /// replaced the call): random magnitudes of texel steps and random bit patterns.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[test]
    fn hypot_gives_the_c_librarys_bits() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..1_000_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let (x, y) = if i % 2 == 0 {
                (
                    f32::from_bits(state as u32),
                    f32::from_bits((state >> 32) as u32),
                )
            } else {
                let unit = |b: u64| (b & 0xff_ffff) as f32 / (1 << 24) as f32 - 0.5;
                (unit(state) * 4096.0, unit(state >> 24) * 4096.0)
            };
            let (ours, libm) = (hypot(x, y), x.hypot(y));
            if libm.is_nan() {
                assert!(ours.is_nan(), "hypot({x:e}, {y:e})");
            } else {
                assert_eq!(ours.to_bits(), libm.to_bits(), "hypot({x:e}, {y:e})");
            }
        }
        for (x, y) in [(f32::INFINITY, f32::NAN), (f32::NAN, f32::NEG_INFINITY)] {
            assert_eq!(hypot(x, y), x.hypot(y), "hypot({x:e}, {y:e})");
        }
    }
}

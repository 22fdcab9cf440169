//! Billboard texture baking and the atlas (improved-billboard-cloud §4,
//! animated-billboard-clouds §2.4), end to end on whatever adapter the machine has
//! (llvmpipe in CI). Tests fail, never skip, when no adapter exists.

use frond_billboard::{
    BakeError, BakeParams, BakedCloud, Plane, Quad, TriangleSoup, bake_cloud, pack,
};
use frond_render::{DrawAlpha, DrawMaterial, DrawTexture, Renderer};
use glam::{Vec2, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn renderer() -> Renderer {
    match Renderer::new() {
        Ok(r) => r,
        Err(e) => panic!("no renderer (CI machines have Mesa llvmpipe): {e}"),
    }
}

/// A quad centred at `center` with the given unit axes and half extents.
fn quad(center: Vec3, axis_u: Vec3, axis_v: Vec3, half: Vec2) -> Quad {
    let normal = axis_u.cross(axis_v);
    Quad {
        plane: Plane {
            normal,
            offset: normal.dot(center),
        },
        center,
        axis_u,
        axis_v,
        half_size: half,
    }
}

fn quad_z(center: Vec3, half: Vec2) -> Quad {
    quad(center, Vec3::X, Vec3::Y, half)
}

/// World point at quad coordinates (s, t) in [0, 1]², plus `depth` along the front normal.
fn at(q: &Quad, s: f32, t: f32, depth: f32) -> Vec3 {
    q.center
        + q.axis_u * (s - 0.5) * 2.0 * q.half_size.x
        + q.axis_v * (t - 0.5) * 2.0 * q.half_size.y
        + q.axis_u.cross(q.axis_v) * depth
}

/// Appends the rectangle `[s0, s1] x [t0, t1]` of quad `q` as two counter-clockwise (seen
/// from the front) triangles with uvs mapping the quad onto the whole texture, upright
/// (t = 1 at the image top).
fn push_rect(soup: &mut TriangleSoup, q: &Quad, s: [f32; 2], t: [f32; 2], material: u32) {
    let p = |s: f32, t: f32| at(q, s, t, 0.0);
    let uv = |s: f32, t: f32| Vec2::new(s, 1.0 - t);
    let corners = [(s[0], t[0]), (s[1], t[0]), (s[1], t[1]), (s[0], t[1])];
    for tri in [[0, 1, 2], [0, 2, 3]] {
        soup.positions
            .push(tri.map(|k| p(corners[k].0, corners[k].1)));
        soup.uvs.push(tri.map(|k| uv(corners[k].0, corners[k].1)));
        soup.material.push(material);
    }
}

fn texel(cloud: &BakedCloud, x: u32, y: u32) -> ([u8; 4], [u8; 4]) {
    let i = (y * cloud.atlas.width + x) as usize * 4;
    let c = &cloud.atlas.color[i..i + 4];
    let n = &cloud.atlas.normal[i..i + 4];
    ([c[0], c[1], c[2], c[3]], [n[0], n[1], n[2], n[3]])
}

/// Atlas texel nearest the given atlas uv.
fn sample(cloud: &BakedCloud, uv: Vec2) -> ([u8; 4], [u8; 4]) {
    let x = (uv.x * cloud.atlas.width as f32).floor() as u32;
    let y = (uv.y * cloud.atlas.height as f32).floor() as u32;
    texel(cloud, x, y)
}

fn near(a: [u8; 4], b: [u8; 4], tol: u8) -> bool {
    a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= tol)
}

fn params(texels_per_unit: f32) -> BakeParams {
    BakeParams {
        texels_per_unit,
        ..BakeParams::default()
    }
}

fn textured(texture: usize) -> DrawMaterial {
    DrawMaterial {
        texture: Some(texture),
        alpha: DrawAlpha::Mask(0.5),
        ..DrawMaterial::default()
    }
}

#[test]
fn a_card_filling_its_quad_reproduces_the_texture() {
    let r = renderer();
    // 16x16 texture: four 8x8 blocks, the bottom-right one transparent.
    let blocks = [
        [[200, 100, 50, 255], [30, 160, 220, 255]],
        [[250, 250, 250, 255], [0, 255, 0, 0]],
    ];
    let mut rgba = Vec::new();
    for y in 0..16 {
        for x in 0..16 {
            rgba.extend(blocks[y / 8][x / 8]);
        }
    }
    let texture = DrawTexture {
        width: 16,
        height: 16,
        rgba,
    };
    let q = quad_z(Vec3::new(1.0, 2.0, 3.0), Vec2::splat(1.0));
    let mut soup = TriangleSoup::default();
    push_rect(&mut soup, &q, [0.0, 1.0], [0.0, 1.0], 0);
    let cloud = bake_cloud(
        &r,
        &soup,
        &[textured(0)],
        &[texture],
        &[q],
        &[vec![0, 1]],
        &params(8.0),
    )
    .expect("bake");
    let cell = cloud.cells[0];
    assert_eq!((cell.width, cell.height), (16, 16));
    assert!(!cloud.density_reduced);
    assert_eq!(cloud.texels_per_unit, 8.0);
    assert_eq!(
        cloud.texture_bytes,
        (cloud.atlas.width * cloud.atlas.height * 8) as usize
    );
    // Away from block borders (bilinear source sampling blends there) the colours and
    // alpha come back exactly; the transparent block is uncovered but not black.
    let mut checked = 0;
    for y in 0..16u32 {
        for x in 0..16u32 {
            let border = |v: u32| v == 0 || v == 7 || v == 8 || v == 15;
            if border(x) || border(y) {
                continue;
            }
            let want = blocks[y as usize / 8][x as usize / 8];
            let (got, normal) = texel(&cloud, cell.x + x, cell.y + y);
            if want[3] == 0 {
                assert_eq!(got[3], 0, "({x},{y}) should be transparent");
                assert_ne!(&got[..3], &[0, 0, 0], "({x},{y}) dilated colour");
                assert_eq!(normal[3], 0);
            } else {
                assert!(near(got, want, 2), "({x},{y}): {got:?} vs {want:?}");
                assert!(near(normal, [128, 128, 255, 255], 1), "normal {normal:?}");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 144);
}

/// The quad `q` baked with an opaque red rectangle and an opaque green one, each
/// `[[s0, s1], [t0, t1]]` of the quad.
fn bake_red_and_green(
    r: &Renderer,
    q: Quad,
    [red, green]: [[[f32; 2]; 2]; 2],
    params: &BakeParams,
) -> BakedCloud {
    let mut soup = TriangleSoup::default();
    push_rect(&mut soup, &q, red[0], red[1], 0);
    push_rect(&mut soup, &q, green[0], green[1], 1);
    let materials = [
        DrawMaterial::opaque([1.0, 0.0, 0.0, 1.0]),
        DrawMaterial::opaque([0.0, 1.0, 0.0, 1.0]),
    ];
    bake_cloud(r, &soup, &materials, &[], &[q], &[vec![0, 1, 2, 3]], params).expect("bake")
}

#[test]
fn downsampling_averages_covered_samples_in_linear_light() {
    let r = renderer();
    // Quad 1x1 at 4 texels per unit: 4x4 texels. Red covers s in [0, 0.375], green
    // [0.375, 1] in the top half only: texel column 1 is half red, half green (top) or half
    // red over nothing (bottom).
    let q = quad_z(Vec3::ZERO, Vec2::splat(0.5));
    let red_green = [[[0.0, 0.375], [0.0, 1.0]], [[0.375, 1.0], [0.5, 1.0]]];
    let cloud = bake_red_and_green(&r, q, red_green, &params(4.0));
    let c = cloud.cells[0];
    assert_eq!((c.width, c.height), (4, 4));
    // Bottom rows (t < 0.5 -> image rows 2, 3): column 1 is 50% red over nothing.
    for y in [2, 3] {
        let (half_red, _) = texel(&cloud, c.x + 1, c.y + y);
        assert_eq!(
            half_red,
            [255, 0, 0, 128],
            "stays pure red, alpha at the cutoff"
        );
        let (red, _) = texel(&cloud, c.x, c.y + y);
        assert_eq!(red, [255, 0, 0, 255]);
    }
    // Uncovered texels copy the nearest covered one: (2, 3) is next to red (1, 3), (3, 2)
    // next to green (3, 1).
    let (empty, _) = texel(&cloud, c.x + 2, c.y + 3);
    assert_eq!(empty, [255, 0, 0, 0]);
    let (empty, _) = texel(&cloud, c.x + 3, c.y + 2);
    assert_eq!(empty, [0, 255, 0, 0]);
    // Top rows: column 1 is half red, half green: linear 0.5 each is sRGB 188, not 128.
    for y in [0, 1] {
        let (mix, _) = texel(&cloud, c.x + 1, c.y + y);
        assert!(near(mix, [188, 188, 0, 255], 1), "{mix:?}");
        let (green, _) = texel(&cloud, c.x + 3, c.y + y);
        assert_eq!(green, [0, 255, 0, 255]);
    }
}

#[test]
fn a_bake_wider_than_one_target_has_no_seam() {
    let r = renderer();
    // 2304×32 texels at 16×16 supersampling: 36,864 samples across, more than one target
    // holds (32,768), so the CPU rasteriser draws it in two frames side by side. Red left of
    // s = 0.25, green right of it; the frames meet at texel 2048 of the atlas.
    let q = quad_z(Vec3::ZERO, Vec2::new(1.125, 1.0 / 64.0));
    let red_green = [[[0.0, 0.25], [0.0, 1.0]], [[0.25, 1.0], [0.0, 1.0]]];
    let params = BakeParams {
        supersample: 16,
        max_side: 4096,
        ..params(1024.0)
    };
    let cloud = bake_red_and_green(&r, q, red_green, &params);
    let c = cloud.cells[0];
    assert_eq!((c.width, c.height), (2304, 32));
    assert!((c.x..c.x + c.width).contains(&(32768 / 16)));
    // Every texel is wholly red or green (their edge is a texel edge), across the frames'
    // meeting line too.
    for y in 0..c.height {
        for x in 0..c.width {
            let (colour, normal) = texel(&cloud, c.x + x, c.y + y);
            let want = if x < 576 {
                [255, 0, 0, 255]
            } else {
                [0, 255, 0, 255]
            };
            assert_eq!(colour, want, "texel ({x}, {y})");
            assert!(near(normal, [128, 128, 255, 255], 1), "normal {normal:?}");
        }
    }
}

/// Several quads in different orientations, each with sparse random leaves (triangles
/// slightly off its plane) of one of three colours.
fn leafy_cloud(
    seed: u64,
    quads: usize,
    leaves: usize,
) -> (TriangleSoup, Vec<Quad>, Vec<Vec<usize>>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut soup = TriangleSoup::default();
    let mut qs = Vec::new();
    let mut members = Vec::new();
    for i in 0..quads {
        let n = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        let plane = Plane {
            normal: n,
            offset: 0.0,
        };
        let (u, v) = plane.frame();
        let center = Vec3::new(
            rng.random_range(-5.0..5.0),
            rng.random_range(0.0..10.0),
            rng.random_range(-5.0..5.0),
        );
        let half = Vec2::new(rng.random_range(0.2..0.8), rng.random_range(0.2..0.8));
        let q = quad(center, u, v, half);
        let mut list = Vec::new();
        for _ in 0..leaves {
            let s: f32 = rng.random_range(0.05..0.95);
            let t: f32 = rng.random_range(0.05..0.95);
            let r = 0.08;
            let corners = [0.0f32, 2.1, 4.2].map(|a| {
                let (ss, cc) = (a + s * 7.0).sin_cos();
                let depth = rng.random_range(-0.05..0.05);
                at(
                    &q,
                    (s + r * cc).clamp(0.0, 1.0),
                    (t + r * ss).clamp(0.0, 1.0),
                    depth,
                )
            });
            list.push(soup.positions.len());
            soup.positions.push(corners);
            soup.uvs.push([Vec2::ZERO, Vec2::X, Vec2::Y]);
            soup.material.push(((i + list.len()) % 3) as u32);
        }
        qs.push(q);
        members.push(list);
    }
    (soup, qs, members)
}

fn leaf_materials() -> Vec<DrawMaterial> {
    [
        [0.8, 0.3, 0.1, 1.0],
        [0.1, 0.6, 0.2, 1.0],
        [0.3, 0.3, 0.9, 1.0],
    ]
    .into_iter()
    .map(|c| DrawMaterial {
        double_sided: false, // baking draws both sides anyway
        ..DrawMaterial::opaque(c)
    })
    .collect()
}

#[test]
fn dilation_fills_every_padded_cell_with_its_own_colours() {
    let r = renderer();
    let (soup, quads, members) = leafy_cloud(7, 12, 6);
    let p = BakeParams {
        padding: 4,
        ..params(24.0)
    };
    let cloud = bake_cloud(&r, &soup, &leaf_materials(), &[], &quads, &members, &p).expect("bake");
    let pad = p.padding;
    for (q, c) in cloud.cells.iter().enumerate() {
        let mut own = std::collections::BTreeSet::new();
        for y in c.y..c.y + c.height {
            for x in c.x..c.x + c.width {
                let (col, _) = texel(&cloud, x, y);
                if col[3] > 0 {
                    own.insert([col[0], col[1], col[2]]);
                }
            }
        }
        assert!(!own.is_empty(), "quad {q} has covered texels");
        let mut uncovered = 0;
        for y in c.y - pad..c.y + c.height + pad {
            for x in c.x - pad..c.x + c.width + pad {
                let (col, normal) = texel(&cloud, x, y);
                if col[3] == 0 {
                    uncovered += 1;
                    assert_ne!(&col[..3], &[0, 0, 0], "quad {q} ({x},{y}) black");
                    assert!(
                        own.contains(&[col[0], col[1], col[2]]),
                        "quad {q} ({x},{y}) {col:?} comes from another quad"
                    );
                    assert_ne!(&normal[..3], &[0, 0, 0], "normal dilated too");
                    assert_eq!(normal[3], 0);
                }
            }
        }
        assert!(uncovered > 0);
    }
}

#[test]
fn uv_rects_map_each_corner_to_its_cell() {
    let r = renderer();
    // 8x8 texture of 4x4 blocks: the block nearest each quad corner k has colour k (blocks,
    // not single texels, so bilinear filtering of the source stays pure inside them).
    let colors = [
        [255, 0, 0, 255],
        [0, 255, 0, 255],
        [0, 0, 255, 255],
        [255, 255, 0, 255],
    ];
    // Image texel (x, y) -> corner: (0,1) is corner 0 (s=0,t=0), (1,1) corner 1, (1,0)
    // corner 2, (0,0) corner 3.
    let blocks = [[3, 2], [0, 1]];
    let mut rgba = Vec::new();
    for y in 0..8 {
        for x in 0..8 {
            rgba.extend(colors[blocks[y / 4][x / 4]]);
        }
    }
    let texture = DrawTexture {
        width: 8,
        height: 8,
        rgba,
    };
    let s2 = std::f32::consts::FRAC_1_SQRT_2;
    let quads = vec![
        quad_z(Vec3::ZERO, Vec2::new(1.0, 0.5)),
        quad(Vec3::X * 3.0, -Vec3::Z, Vec3::Y, Vec2::new(0.3, 0.9)), // faces +X
        quad(Vec3::Y * 2.0, Vec3::X, -Vec3::Z, Vec2::new(0.6, 0.6)), // faces +Y
        quad(
            Vec3::new(-2.0, 1.0, 1.0),
            Vec3::new(s2, 0.0, -s2),
            Vec3::new(0.0, 1.0, 0.0),
            Vec2::new(0.4, 0.7),
        ),
    ];
    let mut soup = TriangleSoup::default();
    let mut members = Vec::new();
    for q in &quads {
        members.push(vec![soup.len(), soup.len() + 1]);
        push_rect(&mut soup, q, [0.0, 1.0], [0.0, 1.0], 0);
    }
    // A magenta member slightly in front of quad 0's corner 2, reaching far outside the
    // quad: it must be clipped to quad 0's cell.
    soup.positions.push([
        at(&quads[0], 0.9, 0.9, 0.01),
        at(&quads[0], 5.0, 0.9, 0.01),
        at(&quads[0], 0.9, 5.0, 0.01),
    ]);
    soup.uvs.push([Vec2::ZERO; 3]);
    soup.material.push(1);
    members[0].push(soup.len() - 1);
    let magenta = [255, 0, 255, 255];

    let cloud = bake_cloud(
        &r,
        &soup,
        &[textured(0), DrawMaterial::opaque([1.0, 0.0, 1.0, 1.0])],
        &[texture],
        &quads,
        &members,
        &params(20.0),
    )
    .expect("bake");
    for (q, rect) in cloud.uv_rects.iter().enumerate() {
        let centre = (rect[0] + rect[2]) * 0.5;
        for (k, &corner) in rect.iter().enumerate() {
            // A quarter of the way from the corner toward the centre: inside the quadrant
            // nearest the corner, away from blends.
            let uv = corner + (centre - corner) * 0.5;
            let (col, _) = sample(&cloud, uv);
            assert!(near(col, colors[k], 2), "quad {q} corner {k}: {col:?}");
        }
        // The rect spans exactly the cell.
        let c = cloud.cells[q];
        let (w, h) = (cloud.atlas.width as f32, cloud.atlas.height as f32);
        assert_eq!(rect[3], Vec2::new(c.x as f32 / w, c.y as f32 / h));
        assert_eq!(
            rect[1],
            Vec2::new((c.x + c.width) as f32 / w, (c.y + c.height) as f32 / h)
        );
    }
    // Every texel of the other cells is covered by their own card only: the stray triangle
    // did not bleed out of quad 0's cell, where it does show.
    let c = cloud.cells[0];
    let (corner, _) = texel(&cloud, c.x + c.width - 1, c.y);
    assert_eq!(corner, magenta);
    for (q, c) in cloud.cells.iter().enumerate().skip(1) {
        for y in c.y..c.y + c.height {
            for x in c.x..c.x + c.width {
                let (col, _) = texel(&cloud, x, y);
                assert_eq!(col[3], 255, "quad {q} ({x},{y})");
                assert!(!near(col, magenta, 60), "quad {q} ({x},{y}) {col:?}");
            }
        }
    }
}

#[test]
fn small_atlases_lower_the_density_and_keep_every_quad() {
    let r = renderer();
    let (soup, quads, members) = leafy_cloud(3, 50, 2);
    let p = BakeParams {
        max_atlas: 256,
        ..params(64.0)
    };
    let cloud = bake_cloud(&r, &soup, &leaf_materials(), &[], &quads, &members, &p).expect("bake");
    assert!(cloud.density_reduced);
    assert!(cloud.texels_per_unit < 64.0);
    assert!(cloud.atlas.width <= 256 && cloud.atlas.height <= 256);
    assert_eq!(cloud.atlas.width % 4, 0);
    assert_eq!(cloud.atlas.height % 4, 0);
    assert_eq!(cloud.cells.len(), 50);
    assert_eq!(cloud.uv_rects.len(), 50);
    let pad = p.padding;
    for (i, a) in cloud.cells.iter().enumerate() {
        // Sizes follow the density actually used.
        let side = quads[i].size() * cloud.texels_per_unit;
        assert_eq!(
            a.width,
            (side.x.ceil() as u32).clamp(p.min_side, p.max_side)
        );
        assert_eq!(
            a.height,
            (side.y.ceil() as u32).clamp(p.min_side, p.max_side)
        );
        assert!(a.x >= pad && a.y >= pad);
        assert!(a.x + a.width + pad <= cloud.atlas.width);
        assert!(a.y + a.height + pad <= cloud.atlas.height);
        for b in &cloud.cells[i + 1..] {
            let apart = a.x + a.width + pad <= b.x - pad
                || b.x + b.width + pad <= a.x - pad
                || a.y + a.height + pad <= b.y - pad
                || b.y + b.height + pad <= a.y - pad;
            assert!(apart, "padded cells {a:?} and {b:?} overlap");
        }
    }
    // At the requested density it would not have fitted.
    let full: Vec<(u32, u32)> = quads
        .iter()
        .map(|q| {
            let s = q.size() * 64.0;
            (s.x.ceil() as u32, s.y.ceil() as u32)
        })
        .collect();
    assert!(pack(&full, pad, 256).is_none());

    // Even the smallest textures cannot fit: an error, not a dropped quad.
    let tiny = BakeParams { max_atlas: 32, ..p };
    assert!(matches!(
        bake_cloud(&r, &soup, &leaf_materials(), &[], &quads, &members, &tiny),
        Err(BakeError::AtlasTooSmall { quads: 50, .. })
    ));
}

#[test]
fn normal_atlas_of_a_front_facing_card_points_to_the_viewer() {
    let r = renderer();
    let q = quad_z(Vec3::ZERO, Vec2::splat(0.5));
    let mut soup = TriangleSoup::default();
    // Left half wound counter-clockwise (front), right half clockwise (its back faces the
    // quad's front): both bake to +Z, the side the billboard shows.
    push_rect(&mut soup, &q, [0.0, 0.5], [0.0, 1.0], 0);
    push_rect(&mut soup, &q, [0.5, 1.0], [0.0, 1.0], 0);
    for tri in &mut soup.positions[2..] {
        tri.swap(1, 2);
    }
    for uv in &mut soup.uvs[2..] {
        uv.swap(1, 2);
    }
    // A leaf card on a second, tilted quad (world normal (0, 1, 1)/sqrt2).
    let tilted = quad(
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::X,
        Vec3::new(0.0, 1.0, -1.0).normalize(),
        Vec2::splat(0.5),
    );
    let t0 = soup.len();
    push_rect(&mut soup, &tilted, [0.0, 1.0], [0.0, 1.0], 0);
    let cloud = bake_cloud(
        &r,
        &soup,
        &[DrawMaterial::opaque([0.5, 0.5, 0.5, 1.0])],
        &[],
        &[q, tilted],
        &[vec![0, 1, 2, 3], vec![t0, t0 + 1]],
        &params(16.0),
    )
    .expect("bake");
    let c = cloud.cells[0];
    for y in c.y..c.y + c.height {
        for x in c.x..c.x + c.width {
            let (col, n) = texel(&cloud, x, y);
            assert_eq!(col[3], 255);
            assert!(near(n, [128, 128, 255, 255], 1), "({x},{y}) {n:?}");
        }
    }
    // The atlas is a tangent-space normal map: a card lying in its own quad reads +Z in that
    // quad's frame however the quad is turned in the world (here tilted 45°).
    let c = cloud.cells[1];
    let (_, n) = texel(&cloud, c.x + c.width / 2, c.y + c.height / 2);
    assert!(near(n, [128, 128, 255, 255], 1), "{n:?}");
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let r = renderer();
    let (soup, quads, members) = leafy_cloud(11, 30, 8);
    let bake = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        pool.install(|| {
            bake_cloud(
                &r,
                &soup,
                &leaf_materials(),
                &[],
                &quads,
                &members,
                &params(30.0),
            )
        })
        .expect("bake")
    };
    let one = bake(1);
    assert_eq!(one, bake(3));
    assert_eq!(one, bake(1));
}

#[test]
fn bad_input_is_an_error() {
    let r = renderer();
    let (soup, quads, members) = leafy_cloud(5, 3, 2);
    let m = leaf_materials();
    let run = |soup: &TriangleSoup, quads: &[Quad], members: &[Vec<usize>], p: &BakeParams| {
        bake_cloud(&r, soup, &m, &[], quads, members, p)
    };
    let p = params(10.0);
    let mut bad_members = members.clone();
    bad_members[1].push(soup.len());
    assert!(matches!(
        run(&soup, &quads, &bad_members, &p),
        Err(BakeError::InvalidInput(_))
    ));
    assert!(matches!(
        run(&soup, &quads, &members[..2], &p),
        Err(BakeError::InvalidInput(_))
    ));
    let mut bad_soup = soup.clone();
    bad_soup.material[0] = 9;
    assert!(matches!(
        run(&bad_soup, &quads, &members, &p),
        Err(BakeError::InvalidInput(_))
    ));
    let mut bad_quads = quads.clone();
    bad_quads[0].center.x = f32::NAN;
    assert!(matches!(
        run(&soup, &bad_quads, &members, &p),
        Err(BakeError::InvalidInput(_))
    ));
    for bad in [
        BakeParams {
            texels_per_unit: 0.0,
            ..p.clone()
        },
        BakeParams {
            supersample: 0,
            ..p.clone()
        },
        BakeParams {
            min_side: 8,
            max_side: 4,
            ..p.clone()
        },
        BakeParams {
            alpha_cutoff: 0.0,
            ..p.clone()
        },
        BakeParams {
            max_atlas: 1 << 20,
            ..p.clone()
        },
    ] {
        assert!(matches!(
            run(&soup, &quads, &members, &bad),
            Err(BakeError::InvalidParams(_))
        ));
    }
    // A texture index the renderer does not have is reported, not a panic.
    let cloud = bake_cloud(&r, &soup, &vec![textured(3); 3], &[], &quads, &members, &p);
    assert!(matches!(cloud, Err(BakeError::Render(_))));
    // No quads: an empty 4x4 atlas.
    let empty = run(&soup, &[], &[], &p).expect("bake");
    assert_eq!((empty.atlas.width, empty.atlas.height), (4, 4));
    assert!(empty.atlas.color.iter().all(|&b| b == 0));
}

/// A 256x256 leaf texture: a green ellipse (alpha 255) on transparent ground.
fn leaf_texture() -> DrawTexture {
    let mut rgba = Vec::with_capacity(256 * 256 * 4);
    for y in 0..256 {
        for x in 0..256 {
            let (u, v) = ((x as f32 - 127.5) / 128.0, (y as f32 - 127.5) / 128.0);
            let inside = u * u + v * v * 2.5 < 1.0;
            let g = 120 + ((x * 7 + y * 3) % 60) as u8;
            rgba.extend([40, g, 30, if inside { 255 } else { 0 }]);
        }
    }
    DrawTexture {
        width: 256,
        height: 256,
        rgba,
    }
}

/// `quads` quads sharing about 50k textured, alpha-tested leaf triangles.
fn timing_cloud(quads: usize) -> (TriangleSoup, Vec<Quad>, Vec<Vec<usize>>) {
    let per_quad = 50_000 / quads;
    let (mut soup, qs, members) = leafy_cloud(42, quads, per_quad);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for uv in &mut soup.uvs {
        let o = Vec2::new(rng.random_range(0.0..0.5), rng.random_range(0.0..0.5));
        *uv = [o, o + Vec2::new(0.5, 0.0), o + Vec2::new(0.25, 0.5)];
    }
    for m in &mut soup.material {
        *m = 0;
    }
    (soup, qs, members)
}

/// Bake timings for ~200 and ~2000 quads with ~50k triangles: a heavy case, in `.ci/run`'s
/// optimised run (`--nocapture` shows the figures).
#[test]
fn heavy_timing_200_and_2000_quads() {
    if !heavy() {
        return;
    }
    let r = renderer();
    eprintln!("adapter: {}", r.adapter_info());
    let material = DrawMaterial {
        texture: Some(0),
        alpha: DrawAlpha::Mask(0.5),
        double_sided: true,
        ..DrawMaterial::default()
    };
    let texture = leaf_texture();
    for (quads, density) in [(200, 64.0), (2000, 64.0), (2000, 32.0), (200, 128.0)] {
        let (soup, qs, members) = timing_cloud(quads);
        let start = std::time::Instant::now();
        let cloud = bake_cloud(
            &r,
            &soup,
            std::slice::from_ref(&material),
            std::slice::from_ref(&texture),
            &qs,
            &members,
            &params(density),
        )
        .expect("bake");
        let covered = cloud
            .atlas
            .color
            .chunks_exact(4)
            .filter(|p| p[3] >= 128)
            .count();
        eprintln!(
            "{quads} quads, {} triangles, {density} texels/unit: {:.2} s, atlas {}x{} \
             (density used {:.1}, reduced {}), {:.1}% opaque texels",
            soup.len(),
            start.elapsed().as_secs_f64(),
            cloud.atlas.width,
            cloud.atlas.height,
            cloud.texels_per_unit,
            cloud.density_reduced,
            100.0 * covered as f64 / (cloud.atlas.width * cloud.atlas.height) as f64,
        );
    }
}

/// Whether the heavy cases run ([`frond_testdata::heavy`]); else one skip line.
fn heavy() -> bool {
    frond_testdata::heavy(env!("CARGO_CRATE_NAME"))
}

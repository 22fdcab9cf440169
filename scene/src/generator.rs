//! Sample-tree generator: a skinned, wind-animated tree with bones per branch, alpha-textured
//! leaf cards bound rigidly to their branch bone, and a seamless loop in which every branch level
//! sways at its own integer-multiple frequencies (thesis §1.5: trunk slow, twigs fast).
//! It keeps every bone's keys so tests can compare sampled motion with ground truth.

use std::f32::consts::TAU;

use glam::{Mat4, Quat, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::json;

use crate::gltf_writer::*;

/// Presets: foliage triangles of about 2k, 20k, 200k and 1M, and a slender broadleaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// About 1,000 leaf quads on two branch levels.
    Small,
    /// About 10,000 leaf quads on three branch levels.
    Medium,
    /// About 100,000 leaf quads on three branch levels.
    Large,
    /// About 500,000 leaf quads on four branch levels.
    Xlarge,
    /// A slender broadleaf: about 3,000 large leaves on two branch levels round a trunk a
    /// tenth as thick as the others' (under a pixel wide when the tree is 60 px tall), whose
    /// branches are thinner still: a tree a LOD chain can thin out by dropping its wood.
    Slender,
}

impl Preset {
    /// Parses `small|medium|large|xlarge`.
    pub fn parse(s: &str) -> Option<Preset> {
        Some(match s {
            "small" => Preset::Small,
            "medium" => Preset::Medium,
            "large" => Preset::Large,
            "xlarge" => Preset::Xlarge,
            "slender" => Preset::Slender,
            _ => return None,
        })
    }
    /// Target number of leaf quads (2 triangles each).
    pub fn leaf_quads(self) -> usize {
        match self {
            Preset::Small => 1_000,
            Preset::Medium => 10_000,
            Preset::Large => 100_000,
            Preset::Xlarge => 500_000,
            Preset::Slender => 3_000,
        }
    }
    /// Branching levels below the trunk and children per branch at each level.
    fn branching(self) -> &'static [usize] {
        match self {
            Preset::Small => &[6, 3],
            Preset::Medium => &[8, 4, 3],
            Preset::Large => &[10, 5, 4],
            Preset::Xlarge => &[12, 5, 4, 3],
            Preset::Slender => &[6, 3],
        }
    }
    /// Radius of the trunk at its base, world units (the tree is about 12 units tall).
    fn trunk_radius(self) -> f32 {
        match self {
            Preset::Slender => 0.08,
            _ => 0.45,
        }
    }
}

/// Loop period of the wind clip, seconds.
pub const PERIOD: f32 = 4.0;
/// Keys per second of the wind clip.
pub const KEY_RATE: f32 = 30.0;

/// One generated bone. Rest rotations are identity, so `head` offsets are world-aligned.
#[derive(Clone, Debug)]
pub struct GenBone {
    /// Its node's name (`trunk_k`, or `branch<i>_L<level>_<k>`).
    pub name: String,
    /// Index of its parent bone; None for the trunk's first.
    pub parent: Option<usize>,
    /// Branch level: 0 for the trunk, 1 for its branches, and so on.
    pub level: usize,
    /// Index of the branch it lies on.
    pub branch: usize,
    /// Rest head position in world space.
    pub head: Vec3,
    /// Rotation keys at `GeneratedTree::key_times`.
    pub keys: Vec<Quat>,
}

/// A generated tree: the GLB and the ground truth behind it.
pub struct GeneratedTree {
    /// The tree as a GLB file.
    pub glb: Vec<u8>,
    /// Every bone with its rest head and keys (node order of the GLB's skin).
    pub bones: Vec<GenBone>,
    /// Times of every bone's rotation keys, seconds, over one [`PERIOD`].
    pub key_times: Vec<f32>,
    /// Rest corners of every leaf quad (vertices 4q..4q+3 of mesh "leaves").
    pub leaf_corners: Vec<[Vec3; 4]>,
    /// Bone of every leaf quad.
    pub leaf_bones: Vec<usize>,
    /// Triangles of the wood mesh.
    pub wood_triangles: usize,
    /// Highest branch tip above the ground, world units.
    pub height: f32,
}

impl GeneratedTree {
    /// Summed area of the leaf cards (each a rectangle: |corner₁ − corner₀|·|corner₃ − corner₀|).
    pub fn leaf_card_area(&self) -> f64 {
        self.leaf_corners
            .iter()
            .map(|q| f64::from((q[1] - q[0]).length() * (q[3] - q[0]).length()))
            .sum()
    }

    /// Rotation of bone `b` at time `t`: the keys interpolated as glTF LINEAR specifies
    /// (shortest-path slerp between the surrounding keys).
    pub fn rotation(&self, b: usize, t: f32) -> Quat {
        let keys = &self.bones[b].keys;
        let times = &self.key_times;
        let last = times.len() - 1;
        if t <= times[0] {
            return keys[0];
        }
        if t >= times[last] {
            return keys[last];
        }
        let mut k = 0;
        while times[k + 1] <= t {
            k += 1;
        }
        let u = (t - times[k]) / (times[k + 1] - times[k]);
        let (a, mut c) = (keys[k], keys[k + 1]);
        if a.dot(c) < 0.0 {
            c = -c;
        }
        let dot = a.dot(c).min(1.0);
        let theta = dot.acos();
        if theta < 1e-6 {
            return (a * (1.0 - u) + c * u).normalize();
        }
        let s = theta.sin();
        (a * (((1.0 - u) * theta).sin() / s) + c * ((u * theta).sin() / s)).normalize()
    }

    /// World transform of bone `b` at time `t`, built up the chain from the root.
    pub fn bone_world(&self, b: usize, t: f32) -> Mat4 {
        let bone = &self.bones[b];
        let offset = match bone.parent {
            Some(p) => bone.head - self.bones[p].head,
            None => bone.head,
        };
        let local = Mat4::from_rotation_translation(self.rotation(b, t), offset);
        match bone.parent {
            Some(p) => self.bone_world(p, t) * local,
            None => local,
        }
    }

    /// Where rest point `p`, rigidly bound to bone `b`, is at time `t`.
    pub fn bound_point(&self, b: usize, p: Vec3, t: f32) -> Vec3 {
        self.bone_world(b, t)
            .transform_point3(p - self.bones[b].head)
    }
}

/// One branch of the generated tree (the trunk is level 0): a straight tapering tube.
struct Branch {
    /// Branch level: 0 for the trunk.
    level: usize,
    /// Where it starts (on its parent branch), world units.
    start: Vec3,
    /// Unit direction it grows in.
    dir: Vec3,
    /// Length, world units.
    length: f32,
    /// Radius at its start (the tube tapers toward the tip).
    radius: f32,
    /// Bone of the parent branch this one hangs from.
    parent_bone: Option<usize>,
    /// Its bones, base to tip.
    bones: Vec<usize>,
}

/// Bones along a branch of `level`: more on the trunk and main limbs, which bend in
/// several places.
fn bones_per_branch(level: usize) -> usize {
    match level {
        0 => 4,
        1 => 3,
        _ => 2,
    }
}

/// A unit vector perpendicular to the unit vector `d`.
fn perpendicular(d: Vec3) -> Vec3 {
    let a = if d.x.abs() < 0.9 { Vec3::X } else { Vec3::Z };
    d.cross(a).normalize()
}

/// Generates a tree. Same preset and seed, same bytes.
pub fn generate(preset: Preset, seed: u64) -> Result<GeneratedTree, image::ImageError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let branching = preset.branching();
    let (branches, mut bones) = grow_branches(branching, preset.trunk_radius(), &mut rng);
    let key_times = wind_keys(&mut bones, &mut rng);
    let wood = wood_tubes(&branches);
    let leaves = leaf_cards(preset, branching, &branches, &bones, &mut rng);
    let wood_triangles = wood.indices.len() / 3;
    let glb = write_glb(
        preset,
        seed,
        wood,
        leaves.primitive,
        &bones,
        &key_times,
        &mut rng,
    )?;
    let height = branches
        .iter()
        .map(|b| (b.start + b.dir * b.length).y)
        .fold(0.0f32, f32::max);
    Ok(GeneratedTree {
        glb,
        bones,
        key_times,
        leaf_corners: leaves.corners,
        leaf_bones: leaves.bones,
        wood_triangles,
        height,
    })
}

/// Grows the branches breadth first from the trunk, `branching[level]` children per branch of
/// each level, and gives every branch its bones ([`bones_per_branch`], evenly spaced along it,
/// each the child of the one before and the first the child of the parent branch's bone it
/// hangs from). Returns the branches and the bones (without keys).
fn grow_branches(
    branching: &[usize],
    trunk_radius: f32,
    rng: &mut ChaCha8Rng,
) -> (Vec<Branch>, Vec<GenBone>) {
    let trunk_len = 8.0f32;
    let mut branches = vec![Branch {
        level: 0,
        start: Vec3::ZERO,
        dir: Vec3::new(
            rng.random_range(-0.05..0.05),
            1.0,
            rng.random_range(-0.05..0.05),
        )
        .normalize(),
        length: trunk_len,
        radius: trunk_radius,
        parent_bone: None,
        bones: Vec::new(),
    }];
    let mut bones: Vec<GenBone> = Vec::new();
    let mut i = 0;
    while i < branches.len() {
        // Bones along this branch.
        let nb = bones_per_branch(branches[i].level);
        let (start, dir, length, level) = (
            branches[i].start,
            branches[i].dir,
            branches[i].length,
            branches[i].level,
        );
        for k in 0..nb {
            let parent = if k == 0 {
                branches[i].parent_bone
            } else {
                Some(bones.len() - 1)
            };
            let name = if level == 0 {
                format!("trunk_{k}")
            } else {
                format!("branch{i}_L{level}_{k}")
            };
            bones.push(GenBone {
                name,
                parent,
                level,
                branch: i,
                head: start + dir * (length * k as f32 / nb as f32),
                keys: Vec::new(),
            });
            branches[i].bones.push(bones.len() - 1);
        }
        // Children.
        if level < branching.len() {
            let count = branching[level];
            let phase0 = rng.random_range(0.0..TAU);
            for c in 0..count {
                let along = if level == 0 {
                    0.35 + 0.6 * (c as f32 + rng.random_range(0.0..0.8)) / count as f32
                } else {
                    0.2 + 0.75 * (c as f32 + rng.random_range(0.0..0.8)) / count as f32
                };
                let at = start + dir * (length * along);
                let seg = ((along * nb as f32) as usize).min(nb - 1);
                let azimuth = phase0 + c as f32 * 2.399_963; // golden angle
                let u = perpendicular(dir);
                let w = dir.cross(u);
                let side = u * azimuth.cos() + w * azimuth.sin();
                let tilt = rng.random_range(0.6..1.0f32);
                let up = if level == 0 { 0.35 } else { 0.15 };
                let cdir = (dir * (1.0 - tilt).max(up) + side * tilt).normalize();
                let clen = length
                    * rng.random_range(0.42..0.58)
                    * if level == 0 { 1.0 - 0.4 * along } else { 1.0 };
                let radius = branches[i].radius * 0.45;
                branches.push(Branch {
                    level: level + 1,
                    start: at,
                    dir: cdir,
                    length: clen,
                    radius,
                    parent_bone: Some(branches[i].bones[seg]),
                    bones: Vec::new(),
                });
            }
        }
        i += 1;
    }

    (branches, bones)
}

/// Gives every bone its wind rotation keys over one loop ([`PERIOD`] at [`KEY_RATE`]): per
/// level inherent frequencies (integer cycles per period, so the loop is seamless) and a gust
/// shared by all. Returns the key times.
fn wind_keys(bones: &mut [GenBone], rng: &mut ChaCha8Rng) -> Vec<f32> {
    // Wind keys: per-level inherent frequencies (integer cycles per period), a shared gust.
    let nkeys = (PERIOD * KEY_RATE).round() as usize + 1;
    let key_times: Vec<f32> = (0..nkeys).map(|k| k as f32 / KEY_RATE).collect();
    let gust_phase = rng.random_range(0.0..TAU);
    for b in bones.iter_mut() {
        let (freqs, amp_deg): (&[f32], f32) = match b.level {
            0 => (&[1.0, 2.0], 1.2),
            1 => (&[2.0, 3.0], 2.5),
            2 => (&[3.0, 5.0], 4.0),
            _ => (&[5.0, 8.0], 6.0),
        };
        let amp = amp_deg.to_radians();
        let ph: Vec<f32> = (0..4).map(|_| rng.random_range(0.0..TAU)).collect();
        b.keys = key_times
            .iter()
            .map(|&t| {
                let w = TAU * t / PERIOD;
                let gust = 0.5 * amp * (w + gust_phase).sin();
                let ax =
                    amp * (0.6 * (freqs[0] * w + ph[0]).sin() + 0.4 * (freqs[1] * w + ph[1]).sin());
                let az = gust
                    + amp
                        * (0.6 * (freqs[0] * w + ph[2]).sin() + 0.4 * (freqs[1] * w + ph[3]).sin());
                Quat::from_rotation_x(ax) * Quat::from_rotation_z(az)
            })
            .collect();
    }

    key_times
}

/// The wood primitive: a tube per branch, tapering, with rings at bone heads (weighted half
/// to each bone across the joint) and mid-bones (bound to that bone).
fn wood_tubes(branches: &[Branch]) -> PrimitiveDesc {
    // Wood: a tube per branch, rings at bone heads (blended across the joint) and mid-bones.
    let radial = 6usize;
    let mut wood = PrimitiveDesc {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        joints: Some(Vec::new()),
        weights: Some(Vec::new()),
        ..Default::default()
    };
    for br in branches {
        let nb = br.bones.len();
        let rings = 2 * nb + 1;
        let u = perpendicular(br.dir);
        let w = br.dir.cross(u);
        let base = wood.positions.len() as u32;
        for r in 0..rings {
            let f = r as f32 / (rings - 1) as f32;
            let centre = br.start + br.dir * (br.length * f);
            let radius = br.radius * (1.0 - 0.85 * f);
            let seg = (r / 2).min(nb - 1);
            let (j, wt) = if r % 2 == 0 && r > 0 && r < rings - 1 {
                (
                    [br.bones[seg - 1] as u16, br.bones[seg] as u16, 0, 0],
                    [0.5, 0.5, 0.0, 0.0],
                )
            } else {
                ([br.bones[seg] as u16, 0, 0, 0], [1.0, 0.0, 0.0, 0.0])
            };
            for s in 0..=radial {
                let a = TAU * s as f32 / radial as f32;
                let n = u * a.cos() + w * a.sin();
                wood.positions.push((centre + n * radius).to_array());
                if let Some(v) = wood.normals.as_mut() {
                    v.push(n.to_array())
                }
                if let Some(v) = wood.uvs.as_mut() {
                    v.push([s as f32 / radial as f32, f * br.length * 0.5])
                }
                if let Some(v) = wood.joints.as_mut() {
                    v.push(j)
                }
                if let Some(v) = wood.weights.as_mut() {
                    v.push(wt)
                }
            }
        }
        let row = (radial + 1) as u32;
        for r in 0..(rings - 1) as u32 {
            for s in 0..radial as u32 {
                let a = base + r * row + s;
                let b = a + row;
                wood.indices
                    .extend_from_slice(&[a, a + 1, b, b, a + 1, b + 1]);
            }
        }
    }

    wood
}

/// The leaf cards [`leaf_cards`] made.
struct LeafCards {
    /// The leaves primitive: 4 vertices and 2 triangles per card.
    primitive: PrimitiveDesc,
    /// Rest corners of every card.
    corners: Vec<[Vec3; 4]>,
    /// The bone every card is bound to.
    bones: Vec<usize>,
}

/// Scatters the preset's leaf cards round the bones of the last branch level and the last bone
/// of the level above, each card randomly placed, tilted and spun, bound rigidly to its bone.
fn leaf_cards(
    preset: Preset,
    branching: &[usize],
    branches: &[Branch],
    bones: &[GenBone],
    rng: &mut ChaCha8Rng,
) -> LeafCards {
    // Leaves on the last level's bones and the last bone of the level above.
    let last = branching.len();
    let leaf_bones: Vec<usize> = branches
        .iter()
        .filter(|b| b.level >= last.saturating_sub(1) && b.level > 0)
        .flat_map(|b| {
            if b.level == last {
                b.bones.clone()
            } else {
                vec![*b.bones.last().unwrap_or(&0)]
            }
        })
        .collect();
    let quads = preset.leaf_quads();
    let leaf_size = match preset {
        Preset::Small => 0.9,
        Preset::Medium => 0.6,
        Preset::Large => 0.3,
        Preset::Xlarge => 0.16,
        Preset::Slender => 0.7,
    };
    let mut leaves = PrimitiveDesc {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        joints: Some(Vec::new()),
        weights: Some(Vec::new()),
        ..Default::default()
    };
    let mut leaf_corners = Vec::with_capacity(quads);
    let mut leaf_bone_of_quad = Vec::with_capacity(quads);
    for q in 0..quads {
        let bone = leaf_bones[q % leaf_bones.len().max(1)];
        let br = &branches[bones[bone].branch];
        let seg_len = br.length / br.bones.len() as f32;
        let head = bones[bone].head;
        let centre = head
            + br.dir * rng.random_range(0.0..seg_len)
            + Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.6..1.0),
                rng.random_range(-1.0..1.0),
            ) * (0.45 * seg_len + leaf_size);
        let normal = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(0.2..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize();
        let tangent = perpendicular(normal);
        let bitangent = normal.cross(tangent);
        let spin = rng.random_range(0.0..TAU);
        let (su, sv) = (
            tangent * spin.cos() + bitangent * spin.sin(),
            -tangent * spin.sin() + bitangent * spin.cos(),
        );
        let hw = 0.5 * leaf_size;
        let hh = 0.6 * leaf_size;
        let corners = [
            centre - su * hw - sv * hh,
            centre + su * hw - sv * hh,
            centre + su * hw + sv * hh,
            centre - su * hw + sv * hh,
        ];
        let base = leaves.positions.len() as u32;
        for (c, uv) in corners
            .iter()
            .zip([[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]])
        {
            leaves.positions.push(c.to_array());
            if let Some(v) = leaves.normals.as_mut() {
                v.push(normal.to_array())
            }
            if let Some(v) = leaves.uvs.as_mut() {
                v.push(uv)
            }
            if let Some(v) = leaves.joints.as_mut() {
                v.push([bone as u16, 0, 0, 0])
            }
            if let Some(v) = leaves.weights.as_mut() {
                v.push([1.0, 0.0, 0.0, 0.0])
            }
        }
        leaves
            .indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        leaf_corners.push(corners);
        leaf_bone_of_quad.push(bone);
    }

    LeafCards {
        primitive: leaves,
        corners: leaf_corners,
        bones: leaf_bone_of_quad,
    }
}

/// Writes the GLB: the bark and leaf textures and materials, the two meshes skinned to a
/// joint per bone (rest offsets from the parent's head, inverse binds undoing each head), and
/// the "Wind" clip of the bones' rotation keys at `key_times`.
fn write_glb(
    preset: Preset,
    seed: u64,
    mut wood: PrimitiveDesc,
    mut leaves: PrimitiveDesc,
    bones: &[GenBone],
    key_times: &[f32],
    rng: &mut ChaCha8Rng,
) -> Result<Vec<u8>, image::ImageError> {
    let mut doc = GltfBuilder::new(concat!(
        "frond ",
        env!("CARGO_PKG_VERSION"),
        " sample generator"
    ));
    doc.set_extras(
        json!({ "frond": { "preset": format!("{preset:?}").to_lowercase(), "seed": seed } }),
    );
    let bark = doc.add_texture("bark", &encode_png(64, 64, &bark_texture(rng))?, false);
    let leaf = doc.add_texture("leaf", &encode_png(128, 128, &leaf_texture())?, true);
    let (bark_mat, leaf_mat) = add_tree_materials(&mut doc, bark, leaf);
    wood.material = Some(bark_mat);
    leaves.material = Some(leaf_mat);
    let branches_mesh = doc.add_mesh("branches", &[wood]);
    let leaves_mesh = doc.add_mesh("leaves", &[leaves]);
    let mut joint_nodes = Vec::with_capacity(bones.len());
    for b in bones {
        let offset = match b.parent {
            Some(p) => b.head - bones[p].head,
            None => b.head,
        };
        let node = doc.add_node(NodeDesc {
            name: b.name.clone(),
            translation: Some(offset.to_array()),
            extras: Some(json!({ "branch": b.branch, "level": b.level })),
            ..Default::default()
        });
        joint_nodes.push(node);
        match b.parent {
            Some(p) => doc.add_child(joint_nodes[p], node),
            None => doc.add_root(node),
        }
    }
    let ibms: Vec<Mat4> = bones
        .iter()
        .map(|b| Mat4::from_translation(-b.head))
        .collect();
    let skin = doc.add_skin("tree", &joint_nodes, &ibms, Some(joint_nodes[0]));
    for (name, mesh) in [("branches", branches_mesh), ("leaves", leaves_mesh)] {
        let n = doc.add_node(NodeDesc {
            name: name.into(),
            mesh: Some(mesh),
            skin: Some(skin),
            ..Default::default()
        });
        doc.add_root(n);
    }
    let channels: Vec<ChannelDesc> = bones
        .iter()
        .zip(&joint_nodes)
        .map(|(b, &node)| ChannelDesc {
            node,
            path: ChannelPath::Rotation,
            times: key_times.to_vec(),
            values: b.keys.iter().flat_map(|q| q.to_array()).collect(),
            interpolation: WriteInterpolation::Linear,
        })
        .collect();
    doc.add_animation("Wind", &channels);
    Ok(doc.to_glb())
}

/// A leaf drawn procedurally: an ovate blade with a darker midrib and veins, alpha outside.
fn leaf_texture() -> Vec<u8> {
    let n = 128usize;
    let mut px = vec![0u8; n * n * 4];
    for y in 0..n {
        for x in 0..n {
            // v: 0 at the stem (bottom) to 1 at the tip (top); u: -1..1 across.
            let v = 1.0 - (y as f32 + 0.5) / n as f32;
            let u = ((x as f32 + 0.5) / n as f32) * 2.0 - 1.0;
            let half_width = 0.85 * (std::f32::consts::PI * v.powf(0.8)).sin().max(0.0);
            let inside = v > 0.06 && u.abs() < half_width;
            let stem = v <= 0.08 && u.abs() < 0.05;
            let o = (y * n + x) * 4;
            if inside || stem {
                let vein = ((v * 14.0 - u.abs() * 5.0).sin().abs() < 0.12) as u8 as f32;
                let rib = (u.abs() < 0.035) as u8 as f32;
                let shade = 0.75 + 0.25 * (1.0 - u.abs());
                let g = (150.0 * shade - 40.0 * (rib + 0.5 * vein)).clamp(0.0, 255.0);
                px[o] = (55.0 * shade + 20.0 * rib) as u8;
                px[o + 1] = g as u8;
                px[o + 2] = (35.0 * shade) as u8;
                px[o + 3] = 255;
            }
        }
    }
    px
}

/// Bark: brown with vertical streaks and noise.
fn bark_texture(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let n = 64usize;
    let streak: Vec<f32> = (0..n).map(|_| rng.random_range(0.7..1.0)).collect();
    let mut px = vec![0u8; n * n * 4];
    for y in 0..n {
        for (x, s) in streak.iter().enumerate() {
            let k = s * rng.random_range(0.85..1.0f32);
            let o = (y * n + x) * 4;
            px[o] = (110.0 * k) as u8;
            px[o + 1] = (78.0 * k) as u8;
            px[o + 2] = (52.0 * k) as u8;
            px[o + 3] = 255;
        }
    }
    px
}

/// The sample trees' two materials on `doc`: opaque one-sided "bark" and alpha-tested (cutoff
/// 0.5) double-sided "leaves", textured with `bark` and `leaf`. Returns their indices (bark,
/// leaves). The fuzzing seeds (`fuzz/seedgen`) build their tiny trees with the same pair.
pub fn add_tree_materials(doc: &mut GltfBuilder, bark: usize, leaf: usize) -> (usize, usize) {
    let bark_mat = doc.add_material(&MaterialDesc {
        name: "bark".into(),
        base_color: [1.0; 4],
        base_color_texture: Some(bark),
        normal_texture: None,
        alpha: WriteAlpha::Opaque,
        double_sided: false,
        metallic: 0.0,
        roughness: 0.9,
    });
    let leaf_mat = doc.add_material(&MaterialDesc {
        name: "leaves".into(),
        base_color: [1.0; 4],
        base_color_texture: Some(leaf),
        normal_texture: None,
        alpha: WriteAlpha::Mask(0.5),
        double_sided: true,
        metallic: 0.0,
        roughness: 0.8,
    });
    (bark_mat, leaf_mat)
}

//! One LOD written into a glTF document: the rig's nodes, one skinned mesh (billboards plus
//! skinned parts such as the wood), joints for billboards with their own motion, and the
//! clips' channels (spec gltf-and-toolchain.md "Skins"; animated-billboard-clouds §1.4).
//!
//! Layout per LOD (names get the LOD's suffix in a combined file):
//! `<name>` — the skinned mesh node (identity, at the scene root, as skinned meshes should be);
//! `<name>_rig` — identity root of the rig's nodes, of `frond_static` (an identity joint for
//! anything that does not move) and of one `frond_motion_<i>` joint per distinct own motion.
//! Rig joints have inverse bind = rest world⁻¹, so vertices are in rest-pose world space.

use std::collections::HashMap;

use frond_lod::texture_budget::ImageSizes;
use frond_lod::{AnimatedBillboardCloud, BillboardTexture};
use frond_scene::Rig;
use frond_scene::Tree;
use frond_scene::gltf_writer::*;
use frond_scene::rig::{Interpolation, Property};
use frond_scene::wood::{NO_BONE, WoodMesh};
use glam::Mat4;

use crate::downscale::Downscaler;
use crate::error::ExportError;
use crate::textures::TextureSink;

/// One LOD to write.
pub struct LodInput<'a> {
    /// Name of the LOD's mesh node, e.g. `oak_LOD1`.
    pub name: String,
    /// Materials and textures of `parts`.
    pub tree: &'a Tree,
    /// Makes `tree`'s images smaller where `image_sizes` asks, shared by every LOD of a chain.
    pub images: &'a Downscaler<'a>,
    /// The skeleton; `parts` bones and billboards' `follows` index its nodes.
    pub rig: &'a Rig,
    /// Skinned triangle meshes with the tree's materials (the wood; LOD0's original foliage).
    /// Their `bones` are rig node indices here (or `NO_BONE`).
    pub parts: Vec<&'a WoodMesh>,
    /// The billboards, if any (their rig must be `rig`).
    pub cloud: Option<&'a AnimatedBillboardCloud>,
    /// Rig clips to write (indices into `rig.clips`).
    pub clips: Vec<usize>,
    /// Sizes the parts' images are written at, where smaller than the input's.
    pub image_sizes: &'a ImageSizes,
    /// Billboards leave the skinned mesh and go to a separate unskinned node `<name>_vat`
    /// whose `TEXCOORD_{1+k}` holds `vat_uvs[k][billboard]` on all four corners (vertex
    /// animation textures play them: piece coordinate, pivot).
    pub vat_uvs: Option<Vec<Vec<[f32; 2]>>>,
    /// Spectral animation (`--animation spectral`): billboards stay skinned, each to the node it
    /// follows (own motion comes from the spectral texture, not from joints), with
    /// `spectral_uvs[billboard]` in `TEXCOORD_1` on all four corners.
    pub spectral_uvs: Option<Vec<[f32; 2]>>,
    /// Skin weights as normalized bytes (every LOD but LOD0, which keeps the input's floats):
    /// a quarter of the bytes, 1/255 of a bone's motion at most.
    pub byte_weights: bool,
    /// How baked billboards are lit.
    pub billboard_normals: BillboardNormals,
}

/// How baked billboards are lit (`frond lod --billboard-normals`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BillboardNormals {
    /// The baked normal atlas as the material's `normalTexture` (half the colour atlas's
    /// side: normals vary slower than the alpha outline), over the quad's own normal: each
    /// billboard lit with its leaves' normals, so a LOD lights like the tree it replaces.
    #[default]
    Baked,
    /// Vertex normals pointing away from the crown's centre (the billboards' bounding box
    /// centre), no normal map: the rounded shading foliage tools give tree crowns.
    Crown,
    /// One flat normal per quad, no normal map.
    Flat,
}

/// Channels of one clip written for one LOD (merged by clip name across LODs).
pub struct ClipChannels {
    pub name: String,
    pub channels: Vec<ChannelDesc>,
}

/// What [`add_lod`] added.
pub struct LodNodes {
    /// The skinned mesh node (and the VAT node, if any).
    pub mesh_nodes: Vec<usize>,
    /// The rig's root node.
    pub rig_root: usize,
    pub clips: Vec<ClipChannels>,
    pub joints: usize,
}

/// The billboards of one texture: the atlas (`key` None) or an input material.
struct TextureGroup {
    key: Option<usize>,
    prim: PrimitiveDesc,
    /// Per vertex.
    joints: Vec<[u16; 4]>,
    /// Indices into the cloud's billboards, in order.
    billboards: Vec<usize>,
}

fn interpolation(i: Interpolation) -> WriteInterpolation {
    match i {
        Interpolation::Linear => WriteInterpolation::Linear,
        Interpolation::Step => WriteInterpolation::Step,
        Interpolation::CubicSpline => WriteInterpolation::CubicSpline,
    }
}

/// Adds one LOD's nodes, mesh, skin and materials to `doc`; `suffix` is appended to every
/// node name other than the mesh node's (for combined files). Scene roots are not set here.
pub fn add_lod(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    suffix: &str,
    sink: &mut TextureSink,
) -> Result<LodNodes, ExportError> {
    let rig = lod.rig;
    let rest = rig.rest_world();
    let rig_root = doc.add_node(NodeDesc {
        name: format!("{}_rig", lod.name),
        ..Default::default()
    });
    // The rig's nodes, parents first.
    let mut out_node = vec![usize::MAX; rig.nodes.len()];
    for &i in &rig.order {
        let n = &rig.nodes[i];
        let id = doc.add_node(NodeDesc {
            name: format!("{}{suffix}", n.name),
            translation: Some(n.rest.translation.to_array()),
            rotation: Some(n.rest.rotation.to_array()),
            scale: Some(n.rest.scale.to_array()),
            extras: n.extras.clone(),
            ..Default::default()
        });
        out_node[i] = id;
        match n.parent {
            Some(p) => doc.add_child(out_node[p], id),
            None => doc.add_child(rig_root, id),
        }
    }

    // Joints, created on first use.
    let mut joints: Vec<usize> = Vec::new();
    let mut ibms: Vec<Mat4> = Vec::new();
    let mut joint_of_node: HashMap<usize, u16> = HashMap::new();
    let mut static_joint: Option<u16> = None;
    let mut motion_joints: HashMap<(Option<usize>, Vec<u32>), u16> = HashMap::new();
    let mut motion_channels: Vec<ChannelDesc> = Vec::new();
    let add_joint = |joints: &mut Vec<usize>, ibms: &mut Vec<Mat4>, node: usize, ibm: Mat4| {
        joints.push(node);
        ibms.push(ibm);
        u16::try_from(joints.len() - 1).map_err(|_| ExportError::TooManyJoints)
    };
    let mut joint_for_node = |doc: &mut GltfBuilder,
                              joints: &mut Vec<usize>,
                              ibms: &mut Vec<Mat4>,
                              node: Option<usize>|
     -> Result<u16, ExportError> {
        match node {
            Some(n) => {
                if let Some(&j) = joint_of_node.get(&n) {
                    return Ok(j);
                }
                let j = add_joint(joints, ibms, out_node[n], rest[n].inverse())?;
                joint_of_node.insert(n, j);
                Ok(j)
            }
            None => {
                if let Some(j) = static_joint {
                    return Ok(j);
                }
                let id = doc.add_node(NodeDesc {
                    name: format!("frond_static{suffix}"),
                    ..Default::default()
                });
                doc.add_child(rig_root, id);
                let j = add_joint(joints, ibms, id, Mat4::IDENTITY)?;
                static_joint = Some(j);
                Ok(j)
            }
        }
    };

    let mut prims = Vec::new();
    let mut vat_prims = Vec::new();
    // Billboards: one primitive for those baked into the atlas, one per input material for
    // those that copy an input card (the hybrid cloud), in order of first use.
    if let Some(cloud) = lod.cloud {
        let mut groups: Vec<TextureGroup> = Vec::new();
        // The crown's centre: the middle of the billboards' corners' bounding box.
        let crown_centre = cloud
            .billboards
            .iter()
            .flat_map(|b| b.quad.corners())
            .fold(None, |acc: Option<(glam::Vec3, glam::Vec3)>, c| match acc {
                None => Some((c, c)),
                Some((lo, hi)) => Some((lo.min(c), hi.max(c))),
            })
            .map(|(lo, hi)| 0.5 * (lo + hi));
        let clock = &cloud.clock;
        let n = clock.samples.max(1);
        for (bi, b) in cloud.billboards.iter().enumerate() {
            let joint = if lod.vat_uvs.is_some() {
                0
            } else if lod.spectral_uvs.is_some() {
                joint_for_node(doc, &mut joints, &mut ibms, b.follows)?
            } else {
                match &b.motion {
                    None => joint_for_node(doc, &mut joints, &mut ibms, b.follows)?,
                    Some(m) => {
                        // Local keys of the motion joint: M(t) at the world level, or
                        // Rest_b⁻¹ · M(t) · Rest_b under the followed node.
                        let local: Vec<Mat4> = (0..n)
                            .map(|s| {
                                let mm = Mat4::from(m.at(s, n));
                                match b.follows {
                                    Some(f) => rest[f].inverse() * mm * rest[f],
                                    None => mm,
                                }
                            })
                            .collect();
                        // Exactly equal motions share a joint (the screen budget already made
                        // motions within half a pixel of each other equal).
                        let key: Vec<u32> = local
                            .iter()
                            .flat_map(|m| m.to_cols_array())
                            .map(f32::to_bits)
                            .collect();
                        match motion_joints.get(&(b.follows, key.clone())) {
                            Some(&j) => j,
                            None => {
                                let id = doc.add_node(NodeDesc {
                                    name: format!("frond_motion_{}{suffix}", motion_joints.len()),
                                    ..Default::default()
                                });
                                let (parent, ibm) = match b.follows {
                                    Some(f) => (out_node[f], rest[f].inverse()),
                                    None => (rig_root, Mat4::IDENTITY),
                                };
                                doc.add_child(parent, id);
                                let j = add_joint(&mut joints, &mut ibms, id, ibm)?;
                                motion_joints.insert((b.follows, key), j);
                                let mut times: Vec<f32> = (0..n).map(|s| clock.time(s)).collect();
                                let mut keys = local.clone();
                                if clock.period > 0.0 {
                                    times.push(clock.start + clock.period);
                                    keys.push(local[0]);
                                }
                                let mut tv = Vec::new();
                                let mut rv = Vec::new();
                                let mut prev: Option<glam::Quat> = None;
                                for k in &keys {
                                    let (_, r, t) = k.to_scale_rotation_translation();
                                    // Keep consecutive keys in one hemisphere.
                                    let r = match prev {
                                        Some(p) if p.dot(r) < 0.0 => -r,
                                        _ => r,
                                    };
                                    prev = Some(r);
                                    tv.extend(t.to_array());
                                    rv.extend(r.normalize().to_array());
                                }
                                motion_channels.push(ChannelDesc {
                                    node: id,
                                    path: ChannelPath::Translation,
                                    times: times.clone(),
                                    values: tv,
                                    interpolation: WriteInterpolation::Linear,
                                });
                                motion_channels.push(ChannelDesc {
                                    node: id,
                                    path: ChannelPath::Rotation,
                                    times,
                                    values: rv,
                                    interpolation: WriteInterpolation::Linear,
                                });
                                j
                            }
                        }
                    }
                }
            };
            let (key, texcoords) = match &b.texture {
                BillboardTexture::Atlas => (None, None),
                BillboardTexture::Input {
                    material,
                    texcoords,
                } => (Some(*material), Some(texcoords)),
            };
            let g = match groups.iter().position(|g| g.key == key) {
                Some(g) => g,
                None => {
                    let material = match key {
                        None => sink.billboard_material(
                            doc,
                            &lod.name,
                            &cloud.atlas,
                            lod.billboard_normals == BillboardNormals::Baked,
                        )?,
                        Some(m) => sink.tree_material(doc, lod.images, m, lod.image_sizes)?,
                    };
                    groups.push(TextureGroup {
                        key,
                        prim: PrimitiveDesc {
                            normals: Some(Vec::new()),
                            // The atlas's normal map is in each quad's (u, v, front) frame.
                            tangents: (key.is_none()
                                && lod.billboard_normals == BillboardNormals::Baked)
                                .then(Vec::new),
                            uvs: Some(Vec::new()),
                            byte_weights: lod.byte_weights,
                            material: Some(material),
                            ..Default::default()
                        },
                        joints: Vec::new(),
                        billboards: Vec::new(),
                    });
                    groups.len() - 1
                }
            };
            let TextureGroup {
                prim: p,
                joints: js,
                billboards: members,
                ..
            } = &mut groups[g];
            let base = p.positions.len() as u32;
            // The input's own TEXCOORD_0 where the copy has one (its material is written as
            // the input had it), else the UVs the billboard samples.
            let uvs = texcoords.and_then(|t| t.first()).unwrap_or(&b.uv);
            for (c, uv) in b.quad.corners().iter().zip(uvs) {
                p.positions.push(c.to_array());
                if let Some(nrm) = p.normals.as_mut() {
                    let n = match (lod.billboard_normals, crown_centre) {
                        (BillboardNormals::Crown, Some(o)) => {
                            (*c - o).normalize_or(b.quad.plane.normal)
                        }
                        _ => b.quad.plane.normal,
                    };
                    nrm.push(n.to_array());
                }
                if let Some(t) = p.tangents.as_mut() {
                    // Bitangent = normal × tangent = axis_v, the normal map's +Y (image up).
                    let u = b.quad.axis_u.normalize_or_zero();
                    t.push([u.x, u.y, u.z, 1.0]);
                }
                if let Some(u) = p.uvs.as_mut() {
                    u.push(uv.to_array());
                }
                js.push([joint, 0, 0, 0]);
            }
            p.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            members.push(bi);
        }
        for TextureGroup {
            prim: mut p,
            joints: js,
            billboards: members,
            ..
        } in groups
        {
            // Per-billboard animation coordinates, on all four corners.
            let per_corner = |rows: &[[f32; 2]]| -> Vec<[f32; 2]> {
                members
                    .iter()
                    .flat_map(|&i| [rows.get(i).copied().unwrap_or_default(); 4])
                    .collect()
            };
            if let Some(sets) = &lod.vat_uvs {
                p.extra_uvs = sets.iter().map(|set| per_corner(set)).collect();
                vat_prims.push(p);
            } else {
                // A group holds at least the billboard that made it.
                if let Some(rows) = &lod.spectral_uvs {
                    p.extra_uvs = vec![per_corner(rows)];
                }
                p.weights = Some(vec![[1.0, 0.0, 0.0, 0.0]; js.len()]);
                p.joints = Some(js);
                prims.push(p);
            }
        }
    }
    // Skinned parts with the tree's materials.
    for part in &lod.parts {
        for prim in &part.primitives {
            if prim.indices.is_empty() {
                continue;
            }
            let mat = sink.tree_material(doc, lod.images, prim.material, lod.image_sizes)?;
            // The input's texture coordinate sets as stored (its materials are written as they
            // were, KHR_texture_transform and texCoord included); `uvs` when it carries none.
            let sets = part.texcoords.len().max(1);
            let mut p = PrimitiveDesc {
                normals: Some(Vec::new()),
                uvs: Some(Vec::new()),
                extra_uvs: vec![Vec::new(); sets - 1],
                joints: Some(Vec::new()),
                weights: Some(Vec::new()),
                byte_weights: lod.byte_weights,
                material: Some(mat),
                ..Default::default()
            };
            let mut remap: HashMap<u32, u32> = HashMap::new();
            for &v in &prim.indices {
                let next = p.positions.len() as u32;
                let id = match remap.get(&v) {
                    Some(&id) => id,
                    None => {
                        let vi = v as usize;
                        let (bones, weights) = (part.bones[vi], part.weights[vi]);
                        let mut j = [0u16; 4];
                        let mut w = [0f32; 4];
                        for s in 0..4 {
                            if weights[s] <= 0.0 {
                                continue;
                            }
                            let node = (bones[s] != NO_BONE).then_some(bones[s] as usize);
                            j[s] = joint_for_node(doc, &mut joints, &mut ibms, node)?;
                            w[s] = weights[s];
                        }
                        p.positions.push(part.positions[vi].to_array());
                        if let Some(n) = p.normals.as_mut() {
                            n.push(part.normals[vi].to_array());
                        }
                        if let Some(u) = p.uvs.as_mut() {
                            let uv = match part.texcoords.first() {
                                Some(set) => set.get(vi).copied().unwrap_or_default(),
                                None => part.uvs[vi],
                            };
                            u.push(uv.to_array());
                        }
                        for (out, set) in p.extra_uvs.iter_mut().zip(part.texcoords.iter().skip(1))
                        {
                            out.push(set.get(vi).copied().unwrap_or_default().to_array());
                        }
                        if let Some(jj) = p.joints.as_mut() {
                            jj.push(j);
                        }
                        if let Some(ww) = p.weights.as_mut() {
                            ww.push(w);
                        }
                        remap.insert(v, next);
                        next
                    }
                };
                p.indices.push(id);
            }
            prims.push(p);
        }
    }
    // Zero-weight slots point at joint 0, which always exists once anything is skinned.
    let mut mesh_nodes = Vec::new();
    if !prims.is_empty() {
        let mesh = doc.add_mesh(&lod.name, &prims);
        let skin = doc.add_skin(
            &format!("{}_skin", lod.name),
            &joints,
            &ibms,
            Some(rig_root),
        );
        mesh_nodes.push(doc.add_node(NodeDesc {
            name: lod.name.clone(),
            mesh: Some(mesh),
            skin: Some(skin),
            ..Default::default()
        }));
    }
    if !vat_prims.is_empty() {
        let mesh = doc.add_mesh(&format!("{}_vat", lod.name), &vat_prims);
        mesh_nodes.push(doc.add_node(NodeDesc {
            name: format!("{}_vat", lod.name),
            mesh: Some(mesh),
            ..Default::default()
        }));
    }

    // Clips: the rig's channels (verbatim) plus the motion joints' keys for the clock's clip.
    let clock_clip = lod.cloud.and_then(|c| c.clock.clip);
    let mut clips = Vec::new();
    for &ci in &lod.clips {
        let Some(clip) = rig.clips.get(ci) else {
            continue;
        };
        let mut channels: Vec<ChannelDesc> = clip
            .channels
            .iter()
            .map(|c| {
                let width = if c.property == Property::Rotation {
                    4
                } else {
                    3
                };
                ChannelDesc {
                    node: out_node[c.node],
                    path: match c.property {
                        Property::Translation => ChannelPath::Translation,
                        Property::Rotation => ChannelPath::Rotation,
                        Property::Scale => ChannelPath::Scale,
                    },
                    times: c.times.clone(),
                    values: c
                        .values
                        .iter()
                        .flat_map(|v| v.to_array().into_iter().take(width))
                        .collect(),
                    interpolation: interpolation(c.interpolation),
                }
            })
            .collect();
        if Some(ci) == clock_clip {
            channels.extend(motion_channels.iter().cloned());
        }
        if channels.is_empty() {
            // Keep the clip, its name and its length: a constant key pair on the rig root.
            channels.push(ChannelDesc {
                node: rig_root,
                path: ChannelPath::Translation,
                times: vec![clip.start, clip.end.max(clip.start)],
                values: vec![0.0; 6],
                interpolation: WriteInterpolation::Linear,
            });
            if clip.end <= clip.start {
                channels[0].times.truncate(1);
                channels[0].values.truncate(3);
            }
        }
        clips.push(ClipChannels {
            name: clip.name.clone(),
            channels,
        });
    }
    Ok(LodNodes {
        mesh_nodes,
        rig_root,
        clips,
        joints: joints.len(),
    })
}

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
use frond_lod::{
    AnimatedBillboard, AnimatedBillboardCloud, BillboardTexture, LoopClock, RigidMotion,
};
use frond_scene::Rig;
use frond_scene::Tree;
use frond_scene::gltf_writer::*;
use frond_scene::rig::{Channel, Clip, Interpolation, Property};
use frond_scene::wood::{NO_BONE, WoodMesh, WoodPrimitive};
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
    /// The rig clip's name: channels of the same clip in other LODs join the same animation.
    pub name: String,
    /// The clip's channels on this LOD's nodes (rig channels, then motion joints' keys).
    pub channels: Vec<ChannelDesc>,
}

/// What [`add_lod`] added.
pub struct LodNodes {
    /// The skinned mesh node (and the VAT node, if any).
    pub mesh_nodes: Vec<usize>,
    /// The rig's root node.
    pub rig_root: usize,
    /// Each written rig clip's channels, in the order of [`LodInput::clips`].
    pub clips: Vec<ClipChannels>,
    /// Number of joints made for the LOD's skin.
    pub joints: usize,
}

/// The billboards of one texture: the atlas (`key` None) or an input material.
struct TextureGroup {
    /// The input material whose card the billboards copy; None for the atlas.
    key: Option<usize>,
    /// The group's primitive, joints and weights left out until every billboard is in.
    prim: PrimitiveDesc,
    /// Per vertex.
    joints: Vec<[u16; 4]>,
    /// Indices into the cloud's billboards, in order.
    billboards: Vec<usize>,
}

/// How rig interpolation `i` is written in glTF.
fn interpolation(i: Interpolation) -> WriteInterpolation {
    match i {
        Interpolation::Linear => WriteInterpolation::Linear,
        Interpolation::Step => WriteInterpolation::Step,
        Interpolation::CubicSpline => WriteInterpolation::CubicSpline,
    }
}

/// Adds one LOD's nodes, mesh, skin and materials to `doc`; `suffix` is appended to every
/// node name other than the mesh node's (for combined files). Scene roots are not set here.
///
/// The steps run in the order the document's nodes, meshes, materials and images are
/// numbered in: the rig, the billboards (joints and materials on first use), the skinned
/// parts, the mesh nodes, then the clips.
pub fn add_lod(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    suffix: &str,
    sink: &mut TextureSink,
) -> Result<LodNodes, ExportError> {
    let mut skin = SkinBuilder::new(doc, lod.rig, &lod.name, suffix);
    let (mut prims, vat_prims) = match lod.cloud {
        Some(cloud) => billboard_primitives(doc, lod, cloud, sink, &mut skin)?,
        None => (Vec::new(), Vec::new()),
    };
    part_primitives(doc, lod, sink, &mut skin, &mut prims)?;
    let mesh_nodes = add_mesh_nodes(doc, lod, &skin, &prims, &vat_prims);
    let clips = clip_channels(lod, &skin);
    Ok(LodNodes {
        mesh_nodes,
        rig_root: skin.rig_root,
        clips,
        joints: skin.joints.len(),
    })
}

/// The skin of one LOD as it is built: the rig's nodes in the document, and the joints,
/// created on first use (a rig node's, the static joint, one per distinct own motion), with
/// their inverse bind matrices and the motion joints' animation channels.
struct SkinBuilder<'a> {
    /// Appended to the names of the nodes made here (combined files).
    suffix: &'a str,
    /// Rest-pose world transform of each rig node.
    rest: Vec<Mat4>,
    /// The `<name>_rig` node every rig root and extra joint hangs under.
    rig_root: usize,
    /// The document node of each rig node.
    out_node: Vec<usize>,
    /// The skin's joint nodes, in joint order.
    joints: Vec<usize>,
    /// Each joint's inverse bind matrix.
    ibms: Vec<Mat4>,
    /// The joint of each rig node that has one.
    joint_of_node: HashMap<usize, u16>,
    /// The `frond_static` joint, once something that does not move needed it.
    static_joint: Option<u16>,
    /// Motion joints by followed node and key bits: exactly equal motions share a joint.
    motion_joints: HashMap<(Option<usize>, Vec<u32>), u16>,
    /// The motion joints' translation and rotation channels (for the clock's clip).
    motion_channels: Vec<ChannelDesc>,
}

impl<'a> SkinBuilder<'a> {
    /// Adds `<name>_rig` and the rig's nodes under it, parents first, with their rest
    /// transforms; no joints yet.
    fn new(doc: &mut GltfBuilder, rig: &Rig, name: &str, suffix: &'a str) -> Self {
        let rest = rig.rest_world();
        let rig_root = doc.add_node(NodeDesc {
            name: format!("{name}_rig"),
            ..Default::default()
        });
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
        SkinBuilder {
            suffix,
            rest,
            rig_root,
            out_node,
            joints: Vec::new(),
            ibms: Vec::new(),
            joint_of_node: HashMap::new(),
            static_joint: None,
            motion_joints: HashMap::new(),
            motion_channels: Vec::new(),
        }
    }

    /// Makes `node` the next joint, bound with `ibm`; its index, which must fit a `u16`
    /// (glTF's `JOINTS_0` as written).
    fn add_joint(&mut self, node: usize, ibm: Mat4) -> Result<u16, ExportError> {
        self.joints.push(node);
        self.ibms.push(ibm);
        u16::try_from(self.joints.len() - 1).map_err(|_| ExportError::TooManyJoints)
    }

    /// The joint of rig node `node`, or for None the `frond_static` identity joint (made
    /// under the rig root on first use): vertices that move with that node, or not at all.
    fn joint_for_node(
        &mut self,
        doc: &mut GltfBuilder,
        node: Option<usize>,
    ) -> Result<u16, ExportError> {
        match node {
            Some(n) => {
                if let Some(&j) = self.joint_of_node.get(&n) {
                    return Ok(j);
                }
                let j = self.add_joint(self.out_node[n], self.rest[n].inverse())?;
                self.joint_of_node.insert(n, j);
                Ok(j)
            }
            None => {
                if let Some(j) = self.static_joint {
                    return Ok(j);
                }
                let id = doc.add_node(NodeDesc {
                    name: format!("frond_static{}", self.suffix),
                    ..Default::default()
                });
                doc.add_child(self.rig_root, id);
                let j = self.add_joint(id, Mat4::IDENTITY)?;
                self.static_joint = Some(j);
                Ok(j)
            }
        }
    }

    /// The joint billboard `b`'s corners are bound to: 0 for VAT billboards (not skinned),
    /// the followed node's under spectral animation (own motion comes from the spectral
    /// texture) or without own motion, else a motion joint playing that motion.
    fn billboard_joint(
        &mut self,
        doc: &mut GltfBuilder,
        lod: &LodInput,
        b: &AnimatedBillboard,
        clock: &LoopClock,
    ) -> Result<u16, ExportError> {
        if lod.vat_uvs.is_some() {
            Ok(0)
        } else if lod.spectral_uvs.is_some() {
            self.joint_for_node(doc, b.follows)
        } else {
            match &b.motion {
                None => self.joint_for_node(doc, b.follows),
                Some(m) => self.motion_joint(doc, b.follows, m, clock),
            }
        }
    }

    /// The `frond_motion_<i>` joint playing motion `m` of a billboard following `follows`:
    /// an existing one when an earlier billboard has exactly the same keys, else a new joint
    /// under the followed node (or the rig root) with its channels.
    fn motion_joint(
        &mut self,
        doc: &mut GltfBuilder,
        follows: Option<usize>,
        m: &RigidMotion,
        clock: &LoopClock,
    ) -> Result<u16, ExportError> {
        let n = clock.samples.max(1);
        // Local keys of the motion joint: M(t) at the world level, or
        // Rest_b⁻¹ · M(t) · Rest_b under the followed node.
        let local: Vec<Mat4> = (0..n)
            .map(|s| {
                let mm = Mat4::from(m.at(s, n));
                match follows {
                    Some(f) => self.rest[f].inverse() * mm * self.rest[f],
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
        if let Some(&j) = self.motion_joints.get(&(follows, key.clone())) {
            return Ok(j);
        }
        let id = doc.add_node(NodeDesc {
            name: format!("frond_motion_{}{}", self.motion_joints.len(), self.suffix),
            ..Default::default()
        });
        let (parent, ibm) = match follows {
            Some(f) => (self.out_node[f], self.rest[f].inverse()),
            None => (self.rig_root, Mat4::IDENTITY),
        };
        doc.add_child(parent, id);
        let j = self.add_joint(id, ibm)?;
        self.motion_joints.insert((follows, key), j);
        self.motion_channels
            .extend(motion_joint_channels(id, clock, &local));
        Ok(j)
    }
}

/// The translation and rotation channels of motion joint `node` playing `local` (one key
/// per clock sample; a looping clock repeats the first key at the end of the period).
fn motion_joint_channels(node: usize, clock: &LoopClock, local: &[Mat4]) -> [ChannelDesc; 2] {
    let n = clock.samples.max(1);
    let mut times: Vec<f32> = (0..n).map(|s| clock.time(s)).collect();
    let mut keys = local.to_vec();
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
    [
        ChannelDesc {
            node,
            path: ChannelPath::Translation,
            times: times.clone(),
            values: tv,
            interpolation: WriteInterpolation::Linear,
        },
        ChannelDesc {
            node,
            path: ChannelPath::Rotation,
            times,
            values: rv,
            interpolation: WriteInterpolation::Linear,
        },
    ]
}

/// The billboards' primitives, skinned ones and VAT ones: one for those baked into the
/// atlas, one per input material for those that copy an input card (the hybrid cloud), in
/// order of first use.
fn billboard_primitives(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    cloud: &AnimatedBillboardCloud,
    sink: &mut TextureSink,
    skin: &mut SkinBuilder,
) -> Result<(Vec<PrimitiveDesc>, Vec<PrimitiveDesc>), ExportError> {
    let mut groups: Vec<TextureGroup> = Vec::new();
    let centre = crown_centre(cloud);
    for (bi, b) in cloud.billboards.iter().enumerate() {
        let joint = skin.billboard_joint(doc, lod, b, &cloud.clock)?;
        let (key, texcoords) = match &b.texture {
            BillboardTexture::Atlas => (None, None),
            BillboardTexture::Input {
                material,
                texcoords,
            } => (Some(*material), Some(texcoords)),
        };
        let g = texture_group(&mut groups, doc, lod, cloud, sink, key)?;
        // The input's own TEXCOORD_0 where the copy has one (its material is written as
        // the input had it), else the UVs the billboard samples.
        let uvs = texcoords.and_then(|t| t.first()).unwrap_or(&b.uv);
        groups[g].push_billboard(b, bi, joint, uvs, lod.billboard_normals, centre);
    }
    Ok(group_primitives(groups, lod))
}

/// The crown's centre: the middle of the billboards' corners' bounding box (None without
/// billboards).
fn crown_centre(cloud: &AnimatedBillboardCloud) -> Option<glam::Vec3> {
    cloud
        .billboards
        .iter()
        .flat_map(|b| b.quad.corners())
        .fold(None, |acc: Option<(glam::Vec3, glam::Vec3)>, c| match acc {
            None => Some((c, c)),
            Some((lo, hi)) => Some((lo.min(c), hi.max(c))),
        })
        .map(|(lo, hi)| 0.5 * (lo + hi))
}

/// The index in `groups` of the group of texture `key`; a new group, with its material
/// written to `doc` now, on the key's first use.
fn texture_group(
    groups: &mut Vec<TextureGroup>,
    doc: &mut GltfBuilder,
    lod: &LodInput,
    cloud: &AnimatedBillboardCloud,
    sink: &mut TextureSink,
    key: Option<usize>,
) -> Result<usize, ExportError> {
    if let Some(g) = groups.iter().position(|g| g.key == key) {
        return Ok(g);
    }
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
            tangents: (key.is_none() && lod.billboard_normals == BillboardNormals::Baked)
                .then(Vec::new),
            uvs: Some(Vec::new()),
            byte_weights: lod.byte_weights,
            material: Some(material),
            ..Default::default()
        },
        joints: Vec::new(),
        billboards: Vec::new(),
    });
    Ok(groups.len() - 1)
}

impl TextureGroup {
    /// Appends billboard `b` (index `index` in the cloud) as a quad of two triangles bound
    /// to `joint`, its corners sampling `uvs` and lit as `normals` asks (`crown_centre` for
    /// crown normals).
    fn push_billboard(
        &mut self,
        b: &AnimatedBillboard,
        index: usize,
        joint: u16,
        uvs: &[glam::Vec2; 4],
        normals: BillboardNormals,
        crown_centre: Option<glam::Vec3>,
    ) {
        let p = &mut self.prim;
        let base = p.positions.len() as u32;
        for (c, uv) in b.quad.corners().iter().zip(uvs) {
            p.positions.push(c.to_array());
            if let Some(nrm) = p.normals.as_mut() {
                let n = match (normals, crown_centre) {
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
            self.joints.push([joint, 0, 0, 0]);
        }
        p.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        self.billboards.push(index);
    }
}

/// The groups' primitives, in group order: VAT primitives carrying the animation
/// coordinates (`vat_uvs`) unskinned, else skinned primitives (with the spectral
/// coordinates under spectral animation). Returns (skinned, VAT).
fn group_primitives(
    groups: Vec<TextureGroup>,
    lod: &LodInput,
) -> (Vec<PrimitiveDesc>, Vec<PrimitiveDesc>) {
    let mut prims = Vec::new();
    let mut vat_prims = Vec::new();
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
    (prims, vat_prims)
}

/// Appends the skinned parts' primitives (with the tree's materials, written on first use)
/// to `prims`, skipping empty ones.
fn part_primitives(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    sink: &mut TextureSink,
    skin: &mut SkinBuilder,
    prims: &mut Vec<PrimitiveDesc>,
) -> Result<(), ExportError> {
    for part in &lod.parts {
        for prim in &part.primitives {
            if prim.indices.is_empty() {
                continue;
            }
            let mat = sink.tree_material(doc, lod.images, prim.material, lod.image_sizes)?;
            prims.push(part_primitive(doc, lod, part, prim, mat, skin)?);
        }
    }
    Ok(())
}

/// One primitive of a skinned part with material `mat`: the vertices its indices use, in
/// order of first use, each bound to the joints of its bones (made on first use).
fn part_primitive(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    part: &WoodMesh,
    prim: &WoodPrimitive,
    mat: usize,
    skin: &mut SkinBuilder,
) -> Result<PrimitiveDesc, ExportError> {
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
                    j[s] = skin.joint_for_node(doc, node)?;
                    w[s] = weights[s];
                }
                push_part_vertex(&mut p, part, vi, j, w);
                remap.insert(v, next);
                next
            }
        };
        p.indices.push(id);
    }
    Ok(p)
}

/// Appends vertex `vi` of `part` to `p`, bound to joints `j` with weights `w`.
fn push_part_vertex(p: &mut PrimitiveDesc, part: &WoodMesh, vi: usize, j: [u16; 4], w: [f32; 4]) {
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
    for (out, set) in p.extra_uvs.iter_mut().zip(part.texcoords.iter().skip(1)) {
        out.push(set.get(vi).copied().unwrap_or_default().to_array());
    }
    if let Some(jj) = p.joints.as_mut() {
        jj.push(j);
    }
    if let Some(ww) = p.weights.as_mut() {
        ww.push(w);
    }
}

/// Writes the meshes and their nodes: the skinned mesh `<name>` with its skin (when
/// anything is skinned) and the unskinned `<name>_vat` (when there are VAT billboards).
/// Returns the nodes, in that order.
fn add_mesh_nodes(
    doc: &mut GltfBuilder,
    lod: &LodInput,
    skin: &SkinBuilder,
    prims: &[PrimitiveDesc],
    vat_prims: &[PrimitiveDesc],
) -> Vec<usize> {
    // Zero-weight slots point at joint 0, which always exists once anything is skinned.
    let mut mesh_nodes = Vec::new();
    if !prims.is_empty() {
        let mesh = doc.add_mesh(&lod.name, prims);
        let skin = doc.add_skin(
            &format!("{}_skin", lod.name),
            &skin.joints,
            &skin.ibms,
            Some(skin.rig_root),
        );
        mesh_nodes.push(doc.add_node(NodeDesc {
            name: lod.name.clone(),
            mesh: Some(mesh),
            skin: Some(skin),
            ..Default::default()
        }));
    }
    if !vat_prims.is_empty() {
        let mesh = doc.add_mesh(&format!("{}_vat", lod.name), vat_prims);
        mesh_nodes.push(doc.add_node(NodeDesc {
            name: format!("{}_vat", lod.name),
            mesh: Some(mesh),
            ..Default::default()
        }));
    }
    mesh_nodes
}

/// The clips' channels: the rig's channels (verbatim) plus the motion joints' keys for the
/// clock's clip; a clip left without channels keeps its name and length through a constant
/// key pair on the rig root.
fn clip_channels(lod: &LodInput, skin: &SkinBuilder) -> Vec<ClipChannels> {
    let clock_clip = lod.cloud.and_then(|c| c.clock.clip);
    let mut clips = Vec::new();
    for &ci in &lod.clips {
        let Some(clip) = lod.rig.clips.get(ci) else {
            continue;
        };
        let mut channels: Vec<ChannelDesc> = clip
            .channels
            .iter()
            .map(|c| rig_channel(c, &skin.out_node))
            .collect();
        if Some(ci) == clock_clip {
            channels.extend(skin.motion_channels.iter().cloned());
        }
        if channels.is_empty() {
            channels.push(constant_channel(clip, skin.rig_root));
        }
        clips.push(ClipChannels {
            name: clip.name.clone(),
            channels,
        });
    }
    clips
}

/// Rig channel `c` as written, on its node's document node (`out_node`).
fn rig_channel(c: &Channel, out_node: &[usize]) -> ChannelDesc {
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
}

/// A constant translation on `rig_root` over `clip` (one key for a clip without length), so
/// that a clip without channels keeps its name and its length.
fn constant_channel(clip: &Clip, rig_root: usize) -> ChannelDesc {
    let mut channel = ChannelDesc {
        node: rig_root,
        path: ChannelPath::Translation,
        times: vec![clip.start, clip.end.max(clip.start)],
        values: vec![0.0; 6],
        interpolation: WriteInterpolation::Linear,
    };
    if clip.end <= clip.start {
        channel.times.truncate(1);
        channel.values.truncate(3);
    }
    channel
}

//! The one glTF writer: nodes, meshes, skins, animations, materials and images (PNGs frond
//! encodes, or the input's images passed through byte for byte)
//! into a single `.glb` (the sample generator uses it now, `export/` later). Output is
//! deterministic: same calls, same bytes. Follows the rules in spec gltf-and-toolchain.md.

use glam::Mat4;
use serde_json::{Map, Value, json};

/// A node to add.
#[derive(Clone, Debug, Default)]
pub struct NodeDesc {
    /// The node's name.
    pub name: String,
    /// Local translation; None writes none (zero).
    pub translation: Option<[f32; 3]>,
    /// Local rotation quaternion (x, y, z, w); None writes none (identity).
    pub rotation: Option<[f32; 4]>,
    /// Local scale; None writes none (one).
    pub scale: Option<[f32; 3]>,
    /// Index returned by [`GltfBuilder::add_mesh`] of the mesh it shows.
    pub mesh: Option<usize>,
    /// Index returned by [`GltfBuilder::add_skin`] of the skin that deforms its mesh.
    pub skin: Option<usize>,
    /// JSON written as the node's `extras`.
    pub extras: Option<Value>,
}

/// glTF alpha mode of a written material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WriteAlpha {
    /// Alpha ignored (`OPAQUE`).
    Opaque,
    /// Alpha-tested at the given cutoff (`MASK` with `alphaCutoff`).
    Mask(f32),
    /// Alpha-blended (`BLEND`).
    Blend,
}

/// A material to add.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// The material's name.
    pub name: String,
    /// Base colour factor, linear RGBA.
    pub base_color: [f32; 4],
    /// Index returned by [`GltfBuilder::add_texture`].
    pub base_color_texture: Option<usize>,
    /// A tangent-space normal map (`normalTexture`), its texture index.
    pub normal_texture: Option<usize>,
    /// Alpha mode.
    pub alpha: WriteAlpha,
    /// Whether back faces are drawn.
    pub double_sided: bool,
    /// Metallic factor, 0..=1.
    pub metallic: f32,
    /// Roughness factor, 0..=1.
    pub roughness: f32,
}

/// One triangle-list primitive. `joints`/`weights` must come together.
#[derive(Clone, Debug, Default)]
pub struct PrimitiveDesc {
    /// `POSITION` per vertex.
    pub positions: Vec<[f32; 3]>,
    /// `NORMAL` per vertex (unit), if written.
    pub normals: Option<Vec<[f32; 3]>>,
    /// `TANGENT` (xyz unit, w the bitangent's sign): what a normal map is read in.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// `TEXCOORD_0` per vertex, if written.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Further texture coordinate sets: TEXCOORD_1, TEXCOORD_2, ...
    pub extra_uvs: Vec<Vec<[f32; 2]>>,
    /// `JOINTS_0` per vertex: indices into the skin's joints.
    pub joints: Option<Vec<[u16; 4]>>,
    /// `WEIGHTS_0` per vertex, summing to 1.
    pub weights: Option<Vec<[f32; 4]>>,
    /// Write `weights` as normalized unsigned bytes (glTF core: 4 bytes a vertex instead of
    /// 16, every engine reads them) instead of floats; each vertex's four sum to exactly 255.
    pub byte_weights: bool,
    /// Triangle list, 3 indices per triangle.
    pub indices: Vec<u32>,
    /// Index returned by [`GltfBuilder::add_material`], if any.
    pub material: Option<usize>,
}

/// `w` (non-negative, summing to about 1) as normalized bytes summing to exactly 255: each
/// rounded down, the remainder given to the largest fractional parts (ties to the lower slot).
pub fn byte_weights(w: [f32; 4]) -> [u8; 4] {
    let total: f32 = w.iter().map(|v| v.max(0.0)).sum();
    if total <= 0.0 || !total.is_finite() {
        return [255, 0, 0, 0];
    }
    let scaled = w.map(|v| v.max(0.0) / total * 255.0);
    let mut out = scaled.map(|v| v.floor() as u8);
    let given: u32 = out.iter().map(|&v| u32::from(v)).sum();
    let mut order = [0usize, 1, 2, 3];
    order.sort_by(|&a, &b| {
        let fa = scaled[a] - scaled[a].floor();
        let fb = scaled[b] - scaled[b].floor();
        fb.total_cmp(&fa).then(a.cmp(&b))
    });
    for &k in order.iter().take(255usize.saturating_sub(given as usize)) {
        out[k] += 1;
    }
    out
}

/// Animated node property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelPath {
    /// The node's `translation` (3 floats a key).
    Translation,
    /// The node's `rotation` (4 floats a key, a quaternion).
    Rotation,
    /// The node's `scale` (3 floats a key).
    Scale,
}

/// Key interpolation of a written channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WriteInterpolation {
    /// Linear between keys (`LINEAR`, the default).
    #[default]
    Linear,
    /// Each key held until the next (`STEP`).
    Step,
    /// `values` holds in-tangent, value, out-tangent per key.
    CubicSpline,
}

/// One animation channel; `values` is 3 or 4 floats per key (three times that for cubic).
#[derive(Clone, Debug)]
pub struct ChannelDesc {
    /// Index returned by [`GltfBuilder::add_node`] of the node it drives.
    pub node: usize,
    /// The property it drives.
    pub path: ChannelPath,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Key values, flattened (see the struct's doc for the count).
    pub values: Vec<f32>,
    /// How values between keys are found.
    pub interpolation: WriteInterpolation,
}

/// Builds a GLB: add things, then [`GltfBuilder::to_glb`].
#[derive(Default)]
pub struct GltfBuilder {
    generator: String,
    bin: Vec<u8>,
    nodes: Vec<Value>,
    children: Vec<Vec<usize>>,
    meshes: Vec<Value>,
    accessors: Vec<Value>,
    views: Vec<Value>,
    skins: Vec<Value>,
    animations: Vec<Value>,
    materials: Vec<Value>,
    textures: Vec<Value>,
    images: Vec<Value>,
    samplers: Vec<Value>,
    scene_roots: Vec<usize>,
    extras: Option<Value>,
    extensions_used: Vec<String>,
    extensions_required: Vec<String>,
    /// [`GltfBuilder::set_compression`].
    compress: bool,
}

/// JSON numbers for single-precision values, each written as the shortest decimal that reads
/// back as the same `f32` (`0.38`, not the `0.3799999952316284` of its double): a reader
/// parsing it as a float gets the value exactly, and the file is smaller by the digits a
/// double would add. A non-finite value is `null`, as serde_json writes it.
fn f32_numbers(v: &[f32]) -> Value {
    Value::Array(
        v.iter()
            .map(|x| {
                format!("{x}")
                    .parse::<f64>()
                    .ok()
                    .and_then(serde_json::Number::from_f64)
                    .map_or(Value::Null, Value::Number)
            })
            .collect(),
    )
}

fn f32s_to_bytes(v: &[f32]) -> impl Iterator<Item = u8> + '_ {
    v.iter().flat_map(|x| x.to_le_bytes())
}

impl GltfBuilder {
    /// A new, empty document; `generator` goes into `asset.generator`.
    pub fn new(generator: &str) -> Self {
        GltfBuilder {
            generator: generator.to_string(),
            ..Default::default()
        }
    }

    /// Writes the geometry compressed from now on: normals and tangents as normalized bytes,
    /// texture coordinates within 0..1 as normalized shorts (`KHR_mesh_quantization`), rotation
    /// keys as normalized shorts (core glTF), and every vertex, index and animation view
    /// meshoptimizer-encoded (`EXT_meshopt_compression`,
    /// both required: a client without them cannot read the file). Positions stay floats: a
    /// quantized position needs a dequantizing node transform, which skinned meshes ignore.
    pub fn set_compression(&mut self, on: bool) {
        self.compress = on;
    }

    /// Adds an accessor of `count` elements already encoded as `bytes` (`stride` bytes an
    /// element, padding included), for the quantized attributes.
    fn add_encoded(
        &mut self,
        bytes: &[u8],
        [component, count, stride]: [usize; 3],
        ty: &str,
        normalized: bool,
    ) -> usize {
        let view = self.push_view(bytes, Some(34962), Some(stride));
        let mut acc =
            json!({ "bufferView": view, "componentType": component, "count": count, "type": ty });
        if normalized {
            acc["normalized"] = json!(true);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Unit vectors (3 or 4 components) as normalized signed bytes padded to 4 bytes
    /// (`KHR_mesh_quantization`).
    fn add_unit_bytes<const N: usize>(&mut self, data: &[[f32; N]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flat_map(|v| {
                let mut b = [0u8; 4];
                for (o, c) in b.iter_mut().zip(v) {
                    *o = ((c.clamp(-1.0, 1.0) * 127.0).round() as i8) as u8;
                }
                b
            })
            .collect();
        let ty = if N == 3 { "VEC3" } else { "VEC4" };
        self.use_extension("KHR_mesh_quantization");
        self.add_encoded(&bytes, [5120, data.len(), 4], ty, true)
    }

    /// Texture coordinates: as normalized unsigned shorts when compressing and all lie in 0..1
    /// (steps of 1/65535: under a texel of a 16k texture), else floats.
    fn add_texcoords(&mut self, uv: &[[f32; 2]]) -> usize {
        if self.compress && uv.iter().flatten().all(|c| (0.0..=1.0).contains(c)) {
            let bytes: Vec<u8> = uv
                .iter()
                .flatten()
                .flat_map(|c| ((c * 65535.0).round() as u16).to_le_bytes())
                .collect();
            self.use_extension("KHR_mesh_quantization");
            return self.add_encoded(&bytes, [5123, uv.len(), 4], "VEC2", true);
        }
        let flat: Vec<f32> = uv.iter().flatten().copied().collect();
        self.add_floats(&flat, "VEC2", false, Some(34962))
    }

    /// Document-level `extras` (e.g. what produced the file and with which seed).
    pub fn set_extras(&mut self, extras: Value) {
        self.extras = Some(extras);
    }

    fn push_view(&mut self, bytes: &[u8], target: Option<u32>, stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// Adds a float accessor (`ty` "SCALAR", "VEC2", "VEC3", "VEC4", "MAT4"); min/max when asked.
    pub fn add_floats(
        &mut self,
        data: &[f32],
        ty: &str,
        with_bounds: bool,
        target: Option<u32>,
    ) -> usize {
        let width = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            _ => 16,
        };
        let bytes: Vec<u8> = f32s_to_bytes(data).collect();
        let view = self.push_view(&bytes, target, None);
        let count = data.len() / width;
        let mut acc =
            json!({ "bufferView": view, "componentType": 5126, "count": count, "type": ty });
        if with_bounds && count > 0 {
            let mut lo = vec![f32::INFINITY; width];
            let mut hi = vec![f32::NEG_INFINITY; width];
            for row in data.chunks_exact(width) {
                for (c, v) in row.iter().enumerate() {
                    lo[c] = lo[c].min(*v);
                    hi[c] = hi[c].max(*v);
                }
            }
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Adds an unsigned-integer accessor in the smallest type that holds `max_value`
    /// (u8 only when `allow_u8`, since indices may not be u8 everywhere).
    fn add_uints(
        &mut self,
        data: &[u32],
        ty: &str,
        width: usize,
        target: Option<u32>,
        allow_u8: bool,
    ) -> usize {
        let max = data.iter().copied().max().unwrap_or(0);
        let (ctype, bytes): (u32, Vec<u8>) = if allow_u8 && max < 256 {
            (5121, data.iter().map(|&v| v as u8).collect())
        } else if max < 65536 {
            (
                5123,
                data.iter()
                    .flat_map(|&v| (v as u16).to_le_bytes())
                    .collect(),
            )
        } else {
            (5125, data.iter().flat_map(|&v| v.to_le_bytes()).collect())
        };
        let view = self.push_view(&bytes, target, None);
        self.accessors.push(json!({
            "bufferView": view, "componentType": ctype, "count": data.len() / width, "type": ty
        }));
        self.accessors.len() - 1
    }

    /// Renames node `node` (no effect on an index past the nodes).
    pub fn set_node_name(&mut self, node: usize, name: &str) {
        if let Some(n) = self.nodes.get_mut(node) {
            n["name"] = json!(name);
        }
    }

    /// Adds a node and returns its index.
    pub fn add_node(&mut self, d: NodeDesc) -> usize {
        let mut n = Map::new();
        n.insert("name".into(), json!(d.name));
        if let Some(t) = d.translation {
            n.insert("translation".into(), f32_numbers(&t));
        }
        if let Some(r) = d.rotation {
            n.insert("rotation".into(), f32_numbers(&r));
        }
        if let Some(s) = d.scale {
            n.insert("scale".into(), f32_numbers(&s));
        }
        if let Some(m) = d.mesh {
            n.insert("mesh".into(), json!(m));
        }
        if let Some(s) = d.skin {
            n.insert("skin".into(), json!(s));
        }
        if let Some(e) = d.extras {
            n.insert("extras".into(), e);
        }
        self.nodes.push(Value::Object(n));
        self.children.push(Vec::new());
        self.nodes.len() - 1
    }

    /// Sets extension `name` (and optionally the `extras`) of an added node, and lists the
    /// extension in `extensionsUsed`.
    pub fn set_node_extension(
        &mut self,
        node: usize,
        name: &str,
        value: Value,
        extras: Option<Value>,
    ) {
        self.use_extension(name);
        if let Some(n) = self.nodes.get_mut(node) {
            if !n["extensions"].is_object() {
                n["extensions"] = json!({});
            }
            n["extensions"][name] = value;
            if let Some(e) = extras {
                n["extras"] = e;
            }
        }
    }

    /// Makes `child` a child of `parent`.
    pub fn add_child(&mut self, parent: usize, child: usize) {
        self.children[parent].push(child);
    }

    /// Adds `node` to the scene's root list.
    pub fn add_root(&mut self, node: usize) {
        self.scene_roots.push(node);
    }

    /// Lists an extension in `extensionsUsed` (once).
    pub fn use_extension(&mut self, name: &str) {
        if !self.extensions_used.iter().any(|e| e == name) {
            self.extensions_used.push(name.to_string());
        }
    }

    /// Lists an extension in `extensionsRequired` (and `extensionsUsed`), once.
    pub fn require_extension(&mut self, name: &str) {
        self.use_extension(name);
        if !self.extensions_required.iter().any(|e| e == name) {
            self.extensions_required.push(name.to_string());
        }
    }

    /// Makes texture `texture` carry KTX2 image `ktx2` through `KHR_texture_basisu`. With
    /// `keep_source` its core `source` stays as the fallback for clients without the
    /// extension; without, `source` is removed and the extension is required (the
    /// extension's rule: a texture without a fallback needs it in `extensionsRequired`).
    pub fn set_basisu_source(&mut self, texture: usize, ktx2: usize, keep_source: bool) {
        let Some(Value::Object(t)) = self.textures.get_mut(texture) else {
            return;
        };
        let ext = t.entry("extensions").or_insert_with(|| json!({}));
        ext["KHR_texture_basisu"] = json!({ "source": ktx2 });
        if keep_source {
            self.use_extension("KHR_texture_basisu");
        } else {
            t.remove("source");
            self.require_extension("KHR_texture_basisu");
        }
    }

    /// Embeds a PNG image and makes a texture of it (linear filtering with mipmaps,
    /// repeat, or clamp-to-edge when `clamp`).
    pub fn add_texture(&mut self, name: &str, png: &[u8], clamp: bool) -> usize {
        let view = self.push_view(png, None, None);
        self.images
            .push(json!({ "name": name, "mimeType": "image/png", "bufferView": view }));
        self.texture_of_last_image(name, clamp)
    }

    /// A texture of a PNG file referenced by relative `uri` (written next to the glTF).
    pub fn add_texture_uri(&mut self, name: &str, uri: &str, clamp: bool) -> usize {
        self.images
            .push(json!({ "name": name, "mimeType": "image/png", "uri": uri }));
        self.texture_of_last_image(name, clamp)
    }

    fn texture_of_last_image(&mut self, name: &str, clamp: bool) -> usize {
        let wrap = if clamp { 33071 } else { 10497 };
        self.samplers
            .push(json!({ "magFilter": 9729, "minFilter": 9987, "wrapS": wrap, "wrapT": wrap }));
        self.textures.push(json!({
            "name": name, "source": self.images.len() - 1, "sampler": self.samplers.len() - 1
        }));
        self.textures.len() - 1
    }

    /// Embeds encoded image bytes as they are (no re-encoding) with their MIME type; returns the
    /// image index. `name` None writes no name.
    pub fn add_image(&mut self, name: Option<&str>, bytes: &[u8], mime_type: &str) -> usize {
        let view = self.push_view(bytes, None, None);
        let mut image = json!({ "mimeType": mime_type, "bufferView": view });
        if let Some(n) = name {
            image["name"] = json!(n);
        }
        self.images.push(image);
        self.images.len() - 1
    }

    /// An image in a file referenced by relative `uri` (written next to the glTF); returns the
    /// image index.
    pub fn add_image_uri(&mut self, name: Option<&str>, uri: &str, mime_type: &str) -> usize {
        let mut image = json!({ "mimeType": mime_type, "uri": uri });
        if let Some(n) = name {
            image["name"] = json!(n);
        }
        self.images.push(image);
        self.images.len() - 1
    }

    /// Adds a sampler given as its JSON object (wrap modes, filters, name, extras: passed
    /// through as they are); an equal sampler already added is reused. Returns its index.
    pub fn add_sampler(&mut self, sampler: Value) -> usize {
        match self.samplers.iter().position(|s| *s == sampler) {
            Some(i) => i,
            None => {
                self.samplers.push(sampler);
                self.samplers.len() - 1
            }
        }
    }

    /// Adds a texture of image `image` with sampler `sampler` (None: none, the glTF default);
    /// `fields` holds any further members to keep (name, extras), `source`/`sampler` in it are
    /// replaced. Returns the texture index.
    pub fn add_texture_of(&mut self, image: usize, sampler: Option<usize>, fields: Value) -> usize {
        let mut t = match fields {
            Value::Object(m) => m,
            _ => Map::new(),
        };
        t.insert("source".into(), json!(image));
        match sampler {
            Some(s) => t.insert("sampler".into(), json!(s)),
            None => t.remove("sampler"),
        };
        self.textures.push(Value::Object(t));
        self.textures.len() - 1
    }

    /// Adds a material given as its complete JSON object (passed through as it is: its texture
    /// maps' `index` must already be this document's texture indices) and lists `extensions`
    /// in `extensionsUsed`. Returns the material index.
    pub fn add_material_json(&mut self, material: Value, extensions: &[String]) -> usize {
        for e in extensions {
            self.use_extension(e);
        }
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Adds a metallic-roughness material.
    pub fn add_material(&mut self, m: &MaterialDesc) -> usize {
        let mut pbr = json!({
            "baseColorFactor": m.base_color,
            "metallicFactor": m.metallic,
            "roughnessFactor": m.roughness,
        });
        if let Some(t) = m.base_color_texture {
            pbr["baseColorTexture"] = json!({ "index": t });
        }
        let mut mat =
            json!({ "name": m.name, "pbrMetallicRoughness": pbr, "doubleSided": m.double_sided });
        if let Some(t) = m.normal_texture {
            mat["normalTexture"] = json!({ "index": t });
        }
        match m.alpha {
            WriteAlpha::Opaque => {}
            WriteAlpha::Mask(c) => {
                mat["alphaMode"] = json!("MASK");
                mat["alphaCutoff"] = json!(c);
            }
            WriteAlpha::Blend => mat["alphaMode"] = json!("BLEND"),
        }
        self.materials.push(mat);
        self.materials.len() - 1
    }

    /// Adds a mesh of triangle-list primitives.
    pub fn add_mesh(&mut self, name: &str, prims: &[PrimitiveDesc]) -> usize {
        let mut out = Vec::new();
        for p in prims {
            let flat: Vec<f32> = p.positions.iter().flatten().copied().collect();
            let mut attrs = Map::new();
            attrs.insert(
                "POSITION".into(),
                json!(self.add_floats(&flat, "VEC3", true, Some(34962))),
            );
            if let Some(n) = &p.normals {
                let accessor = if self.compress {
                    self.add_unit_bytes(n)
                } else {
                    let flat: Vec<f32> = n.iter().flatten().copied().collect();
                    self.add_floats(&flat, "VEC3", false, Some(34962))
                };
                attrs.insert("NORMAL".into(), json!(accessor));
            }
            if let Some(t) = &p.tangents {
                let accessor = if self.compress {
                    self.add_unit_bytes(t)
                } else {
                    let flat: Vec<f32> = t.iter().flatten().copied().collect();
                    self.add_floats(&flat, "VEC4", false, Some(34962))
                };
                attrs.insert("TANGENT".into(), json!(accessor));
            }
            if let Some(uv) = &p.uvs {
                attrs.insert("TEXCOORD_0".into(), json!(self.add_texcoords(uv)));
            }
            for (k, uv) in p.extra_uvs.iter().enumerate() {
                attrs.insert(format!("TEXCOORD_{}", k + 1), json!(self.add_texcoords(uv)));
            }
            if let (Some(j), Some(w)) = (&p.joints, &p.weights) {
                // A weight that rounds to no byte leaves its slot, pointing at joint 0 as
                // unused slots do (the validator flags a joint used with zero weight).
                let flat: Vec<u32> = j
                    .iter()
                    .zip(w)
                    .flat_map(|(j, w)| {
                        let bytes = p.byte_weights.then(|| byte_weights(*w));
                        (0..4).map(move |k| match bytes {
                            Some(b) if b[k] == 0 => 0,
                            _ => u32::from(j[k]),
                        })
                    })
                    .collect();
                attrs.insert(
                    "JOINTS_0".into(),
                    json!(self.add_uints(&flat, "VEC4", 4, Some(34962), true)),
                );
                let accessor = if p.byte_weights {
                    let bytes: Vec<u8> = w.iter().flat_map(|&v| byte_weights(v)).collect();
                    let view = self.push_view(&bytes, Some(34962), None);
                    self.accessors.push(json!({
                        "bufferView": view, "componentType": 5121, "normalized": true,
                        "count": w.len(), "type": "VEC4"
                    }));
                    self.accessors.len() - 1
                } else {
                    let flat: Vec<f32> = w.iter().flatten().copied().collect();
                    self.add_floats(&flat, "VEC4", false, Some(34962))
                };
                attrs.insert("WEIGHTS_0".into(), json!(accessor));
            }
            let idx = self.add_uints(&p.indices, "SCALAR", 1, Some(34963), false);
            let mut prim = json!({ "attributes": attrs, "indices": idx, "mode": 4 });
            if let Some(m) = p.material {
                prim["material"] = json!(m);
            }
            out.push(prim);
        }
        self.meshes.push(json!({ "name": name, "primitives": out }));
        self.meshes.len() - 1
    }

    /// Adds a skin over `joints` (node indices) with their inverse bind matrices.
    pub fn add_skin(
        &mut self,
        name: &str,
        joints: &[usize],
        inverse_bind: &[Mat4],
        skeleton: Option<usize>,
    ) -> usize {
        // glTF requires affine inverse binds with an exact (0, 0, 0, 1) last row; inverting in
        // f32 leaves 1 ± 1e-7 there, which the validator rejects.
        let flat: Vec<f32> = inverse_bind
            .iter()
            .flat_map(|m| {
                let mut a = m.to_cols_array();
                for i in [3, 7, 11] {
                    a[i] = 0.0;
                }
                a[15] = 1.0;
                a
            })
            .collect();
        let acc = self.add_floats(&flat, "MAT4", false, None);
        let mut skin = json!({ "name": name, "joints": joints, "inverseBindMatrices": acc });
        if let Some(s) = skeleton {
            skin["skeleton"] = json!(s);
        }
        self.skins.push(skin);
        self.skins.len() - 1
    }

    /// Adds an animation clip. Key-time accessors are shared between channels with equal times.
    pub fn add_animation(&mut self, name: &str, channels: &[ChannelDesc]) -> usize {
        let mut samplers = Vec::new();
        let mut chans = Vec::new();
        let mut time_accessors: Vec<(Vec<f32>, usize)> = Vec::new();
        for c in channels {
            let input = match time_accessors.iter().find(|(t, _)| *t == c.times) {
                Some((_, a)) => *a,
                None => {
                    let a = self.add_floats(&c.times, "SCALAR", true, None);
                    time_accessors.push((c.times.clone(), a));
                    a
                }
            };
            let ty = if c.path == ChannelPath::Rotation {
                "VEC4"
            } else {
                "VEC3"
            };
            // Compressed: rotations as normalized shorts (glTF core allows them for rotation
            // outputs; 3e-5 rad a key), half the bytes before meshoptimizer's encoding. Cubic
            // spline tangents are no unit quaternions and stay floats.
            let output = if self.compress
                && c.path == ChannelPath::Rotation
                && c.interpolation != WriteInterpolation::CubicSpline
            {
                let bytes: Vec<u8> = c
                    .values
                    .iter()
                    .flat_map(|v| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16).to_le_bytes())
                    .collect();
                let view = self.push_view(&bytes, None, None);
                self.accessors.push(json!({
                    "bufferView": view, "componentType": 5122, "normalized": true,
                    "count": c.values.len() / 4, "type": "VEC4"
                }));
                self.accessors.len() - 1
            } else {
                self.add_floats(&c.values, ty, false, None)
            };
            samplers.push(json!({
                "input": input, "output": output,
                "interpolation": match c.interpolation {
                    WriteInterpolation::Linear => "LINEAR",
                    WriteInterpolation::Step => "STEP",
                    WriteInterpolation::CubicSpline => "CUBICSPLINE",
                }
            }));
            let path = match c.path {
                ChannelPath::Translation => "translation",
                ChannelPath::Rotation => "rotation",
                ChannelPath::Scale => "scale",
            };
            chans.push(json!({ "sampler": samplers.len() - 1, "target": { "node": c.node, "path": path } }));
        }
        self.animations
            .push(json!({ "name": name, "samplers": samplers, "channels": chans }));
        self.animations.len() - 1
    }

    /// The finished GLB bytes.
    pub fn to_glb(mut self) -> Vec<u8> {
        for (i, kids) in self.children.iter().enumerate() {
            if !kids.is_empty() {
                self.nodes[i]["children"] = json!(kids);
            }
        }
        let fallback = if self.compress {
            self.compress_views()
        } else {
            None
        };
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut root = Map::new();
        root.insert(
            "asset".into(),
            json!({ "version": "2.0", "generator": self.generator }),
        );
        root.insert("scene".into(), json!(0));
        root.insert("scenes".into(), json!([{ "nodes": self.scene_roots }]));
        let mut put = |k: &str, v: Vec<Value>| {
            if !v.is_empty() {
                root.insert(k.into(), Value::Array(v));
            }
        };
        put("nodes", self.nodes);
        put("meshes", self.meshes);
        put("skins", self.skins);
        put("animations", self.animations);
        put("materials", self.materials);
        put("textures", self.textures);
        put("images", self.images);
        put("samplers", self.samplers);
        put("accessors", self.accessors);
        put("bufferViews", self.views);
        if !self.bin.is_empty() || fallback.is_some() {
            let mut buffers = vec![json!({ "byteLength": self.bin.len() })];
            if let Some(len) = fallback {
                buffers.push(json!({
                    "byteLength": len,
                    "extensions": { "EXT_meshopt_compression": { "fallback": true } }
                }));
            }
            root.insert("buffers".into(), Value::Array(buffers));
        }
        if let Some(e) = self.extras {
            root.insert("extras".into(), e);
        }
        if !self.extensions_used.is_empty() {
            root.insert("extensionsUsed".into(), json!(self.extensions_used));
        }
        if !self.extensions_required.is_empty() {
            root.insert("extensionsRequired".into(), json!(self.extensions_required));
        }
        let json_bytes = serde_json::to_vec(&Value::Object(root)).unwrap_or_default();
        glb_container(&json_bytes, &self.bin)
    }
}

impl GltfBuilder {
    /// Meshoptimizer-encodes the views of vertex attributes, triangle indices and animation
    /// keys (`EXT_meshopt_compression`): each such view moves to a fallback buffer without
    /// data (buffer 1, its byte length returned) and names its encoded bytes in the binary
    /// chunk; other views (images, inverse binds) stay as they are. None when no view was
    /// encoded (nothing to compress: no extension, no fallback buffer).
    fn compress_views(&mut self) -> Option<usize> {
        use crate::meshopt_views::{encode_attributes, encode_triangles};
        #[derive(Clone, Copy)]
        enum Role {
            Attributes,
            Triangles { vertices: usize },
        }
        let mut roles: Vec<Option<(Role, usize)>> = vec![None; self.views.len()];
        let accessor = |a: &Value| -> Option<(usize, usize, usize)> {
            let view = a["bufferView"].as_u64()? as usize;
            let count = a["count"].as_u64()? as usize;
            let component = match a["componentType"].as_u64()? {
                5120 | 5121 => 1,
                5122 | 5123 => 2,
                _ => 4,
            };
            let width = match a["type"].as_str()? {
                "SCALAR" => 1,
                "VEC2" => 2,
                "VEC3" => 3,
                "VEC4" => 4,
                _ => 16,
            };
            Some((view, count, component * width))
        };
        let mark = |a: usize, role: Role, roles: &mut Vec<Option<(Role, usize)>>| {
            if let Some((view, count, size)) = self.accessors.get(a).and_then(accessor) {
                let stride = self.views[view]["byteStride"]
                    .as_u64()
                    .map_or(size, |s| s as usize);
                let stride = match role {
                    Role::Attributes => stride,
                    Role::Triangles { .. } => size,
                };
                roles[view] = Some((role, count)).filter(|_| {
                    self.views[view]["byteLength"].as_u64() == Some((count * stride) as u64)
                });
            }
        };
        for mesh in &self.meshes {
            for p in mesh["primitives"].as_array().into_iter().flatten() {
                let mut vertices = 0;
                for a in p["attributes"]
                    .as_object()
                    .into_iter()
                    .flat_map(|m| m.values())
                {
                    if let Some(a) = a.as_u64() {
                        vertices =
                            self.accessors[a as usize]["count"].as_u64().unwrap_or(0) as usize;
                        mark(a as usize, Role::Attributes, &mut roles);
                    }
                }
                if let Some(i) = p["indices"].as_u64() {
                    mark(i as usize, Role::Triangles { vertices }, &mut roles);
                }
            }
        }
        for anim in &self.animations {
            for s in anim["samplers"].as_array().into_iter().flatten() {
                for key in ["input", "output"] {
                    if let Some(a) = s[key].as_u64() {
                        mark(a as usize, Role::Attributes, &mut roles);
                    }
                }
            }
        }
        let old = std::mem::take(&mut self.bin);
        let mut fallback = 0usize;
        let mut any = false;
        for (view, role) in self.views.iter_mut().zip(roles) {
            let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
            let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
            let bytes = &old[offset..offset + length];
            let encoded = role.and_then(|(role, count)| {
                let stride = length.checked_div(count)?;
                let data = match role {
                    Role::Attributes => encode_attributes(bytes, count, stride).ok()?,
                    Role::Triangles { vertices } => {
                        let indices: Vec<u32> = match stride {
                            2 => bytes
                                .chunks_exact(2)
                                .map(|b| u32::from(u16::from_le_bytes([b[0], b[1]])))
                                .collect(),
                            4 => bytes
                                .chunks_exact(4)
                                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                                .collect(),
                            _ => return None,
                        };
                        encode_triangles(&indices, vertices).ok()?
                    }
                };
                let mode = match role {
                    Role::Attributes => "ATTRIBUTES",
                    Role::Triangles { .. } => "TRIANGLES",
                };
                Some((data, mode, stride, count))
            });
            while !self.bin.len().is_multiple_of(4) {
                self.bin.push(0);
            }
            match encoded {
                Some((data, mode, stride, count)) => {
                    fallback = fallback.next_multiple_of(4);
                    view["extensions"] = json!({ "EXT_meshopt_compression": {
                        "buffer": 0, "byteOffset": self.bin.len(), "byteLength": data.len(),
                        "byteStride": stride, "count": count, "mode": mode
                    }});
                    view["buffer"] = json!(1);
                    view["byteOffset"] = json!(fallback);
                    fallback += length;
                    self.bin.extend_from_slice(&data);
                    any = true;
                }
                None => {
                    view["byteOffset"] = json!(self.bin.len());
                    self.bin.extend_from_slice(bytes);
                }
            }
        }
        if !any {
            return None;
        }
        self.require_extension("EXT_meshopt_compression");
        if self
            .extensions_used
            .iter()
            .any(|e| e == "KHR_mesh_quantization")
        {
            self.require_extension("KHR_mesh_quantization");
        }
        Some(fallback)
    }
}

/// Wraps a JSON document and an optional binary chunk in a GLB container (both padded to
/// 4 bytes as the format requires; an empty `bin` writes no BIN chunk).
pub fn glb_container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.next_multiple_of(4);
    let (jl, bl) = (pad(json.len()), pad(bin.len()));
    let total = 12 + 8 + jl + if bin.is_empty() { 0 } else { 8 + bl };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(jl as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(20 + jl, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bl as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    out
}

/// Encodes RGBA8 pixels as PNG.
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, image::ImageError> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(
        rgba,
        width,
        height,
        image::ExtendedColorType::Rgba8,
    )?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_transforms_read_back_as_the_same_floats_in_their_shortest_digits() {
        let values = [
            0.38f32,
            -0.0035507511,
            11.916187,
            1.0,
            1e-10,
            3.4e38,
            f32::MIN_POSITIVE,
            -0.47000188,
        ];
        let text = serde_json::to_string(&f32_numbers(&values)).expect("json");
        let back: Vec<f64> = serde_json::from_str(&text).expect("numbers");
        for (v, b) in values.iter().zip(&back) {
            assert_eq!(*b as f32, *v, "{text}");
        }
        assert!(
            text.starts_with("[0.38,-0.0035507511,11.916187,1.0,"),
            "{text}"
        );
        let double = serde_json::to_string(&json!(values)).expect("json");
        assert!(text.len() < double.len(), "{text} against {double}");
        assert_eq!(f32_numbers(&[f32::NAN]), json!([null]));
    }

    #[test]
    fn byte_weights_sum_to_255_and_round_to_the_nearest() {
        assert_eq!(byte_weights([1.0, 0.0, 0.0, 0.0]), [255, 0, 0, 0]);
        assert_eq!(byte_weights([0.5, 0.5, 0.0, 0.0]), [128, 127, 0, 0]);
        assert_eq!(byte_weights([0.0; 4]), [255, 0, 0, 0]);
        for w in [
            [0.25f32, 0.25, 0.25, 0.25],
            [0.7, 0.2, 0.1, 0.0],
            [0.333, 0.333, 0.334, 0.0],
            [0.9, 0.05, 0.03, 0.02],
        ] {
            let b = byte_weights(w);
            assert_eq!(b.iter().map(|&v| u32::from(v)).sum::<u32>(), 255, "{w:?}");
            for k in 0..4 {
                assert!(
                    (f32::from(b[k]) / 255.0 - w[k]).abs() <= 1.0 / 255.0,
                    "{w:?} {b:?}"
                );
            }
        }
    }
}

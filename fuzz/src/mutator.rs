//! Structure-aware mutation of glTF inputs for libFuzzer's custom-mutator hook.
//!
//! An input is a GLB (or a `.gltf` JSON text). Most mutations parse its JSON chunk into a
//! `serde_json::Value`, apply one to four structured edits chosen with `arbitrary` (accessor
//! counts, offsets, component types; bufferView strides, offsets, lengths; node children,
//! skins, joints; animation samplers, key times; material/texture/image indices;
//! `extensionsRequired`; edge numbers such as 2^32, -1, 1e999, NaN, -0; deep hierarchies,
//! cycles, mesh instancing; new sparse blocks, images and buffer views), write it back, and
//! re-wrap it with its binary chunk (edited too, by some mutations). The rest mutate the JSON bytes, a window of the
//! binary chunk or the container with libFuzzer's own mutator, or edit the container itself.
//! Everything is a deterministic function of (input, seed), as libFuzzer requires.

use arbitrary::{Arbitrary, Unstructured};
use base64::Engine;
use serde_json::{Map, Value, json};

use crate::{join_glb, split_glb, tiny_png};

/// SplitMix64: the mutator's only source of randomness, seeded by libFuzzer.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x5DEE_CE66_D1CE_4E5B)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next_u64() % n as u64) as usize
        }
    }
    pub fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n.div_ceil(8))
            .flat_map(|_| self.next_u64().to_le_bytes())
            .take(n)
            .collect()
    }
}

/// A parsed input: its JSON document and binary chunk.
pub struct Doc {
    /// A `.gltf` JSON text rather than a GLB.
    pub text: bool,
    pub json: Value,
    pub bin: Option<Vec<u8>>,
    /// Raw JSON tokens (1e999, NaN, -0.0, 2^64) that `Value` cannot hold: placeholders in
    /// `json`, substituted when serialized.
    raw: Vec<(String, String)>,
}

impl Doc {
    pub fn parse(bytes: &[u8]) -> Option<Doc> {
        let (json, bin, text) = if bytes.starts_with(b"glTF") {
            let (j, bin) = split_glb(bytes)?;
            let end = j
                .iter()
                .rposition(|&b| b != b' ' && b != 0)
                .map_or(0, |p| p + 1);
            (serde_json::from_slice::<Value>(&j[..end]).ok()?, bin, false)
        } else {
            (serde_json::from_slice::<Value>(bytes).ok()?, None, true)
        };
        json.is_object().then_some(Doc {
            text,
            json,
            bin,
            raw: Vec::new(),
        })
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let mut s = serde_json::to_string(&self.json).unwrap_or_default();
        for (marker, token) in &self.raw {
            s = s.replace(&format!("\"{marker}\""), token);
        }
        if self.text {
            s.into_bytes()
        } else {
            join_glb(s.as_bytes(), self.bin.as_deref())
        }
    }

    fn raw(&mut self, token: &str) -> Value {
        let marker = format!("@@frond-fuzz-raw-{}@@", self.raw.len());
        self.raw.push((marker.clone(), token.to_string()));
        Value::String(marker)
    }

    fn len_of(&self, key: &str) -> usize {
        self.json
            .get(key)
            .and_then(Value::as_array)
            .map_or(0, Vec::len)
    }

    fn array_mut(&mut self, key: &str) -> &mut Vec<Value> {
        let root = self.json.as_object_mut().expect("root is an object");
        let v = root.entry(key).or_insert_with(|| json!([]));
        if !v.is_array() {
            *v = json!([]);
        }
        v.as_array_mut().expect("just made an array")
    }

    /// Appends `bytes` to the binary chunk in a new bufferView; None for JSON-text inputs
    /// whose buffer 0 is a URI.
    fn append_view(&mut self, bytes: &[u8]) -> Option<usize> {
        if self.text {
            return None;
        }
        {
            let buffers = self.array_mut("buffers");
            if buffers.is_empty() {
                buffers.push(json!({ "byteLength": 0 }));
            }
            if buffers[0].get("uri").is_some() || !buffers[0].is_object() {
                return None;
            }
        }
        let bin = self.bin.get_or_insert_with(Vec::new);
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        let total = bin.len();
        if let Some(b) = self.array_mut("buffers")[0].as_object_mut() {
            b.insert("byteLength".into(), json!(total));
        }
        let views = self.array_mut("bufferViews");
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }));
        Some(views.len() - 1)
    }
}

/// The libFuzzer custom mutator: writes a mutant of `data[..size]` into `data` and returns
/// its size (at most `max_size`).
pub fn mutate(data: &mut [u8], size: usize, max_size: usize, seed: u32) -> usize {
    let mut rng = Rng::new(seed as u64);
    let entropy = rng.bytes(2048);
    let mut u = Unstructured::new(&entropy);
    let roll = rng.below(100);
    let out = match Doc::parse(&data[..size]) {
        Some(mut doc) => {
            if roll < 74 {
                structured(&mut doc, &mut u, max_size.saturating_sub(size)).map(|()| doc.to_bytes())
            } else if roll < 80 {
                json_bytes(&doc, max_size)
            } else if roll < 87 {
                bin_window(&mut doc, &mut rng).map(|()| doc.to_bytes())
            } else if roll < 96 {
                container(&mut doc, &mut u)
            } else {
                None
            }
        }
        // A GLB whose JSON no longer parses: mutate the JSON chunk bytes, keep the container.
        None if roll < 60 && data[..size].starts_with(b"glTF") => split_glb(&data[..size])
            .and_then(|(j, bin)| {
                let budget = max_size.saturating_sub(bin.as_ref().map_or(0, Vec::len) + 40);
                let j = byte_mutate(&j, budget.max(j.len()))?;
                Some(join_glb(&j, bin.as_deref()))
            }),
        None => None,
    };
    match out {
        Some(o) if !o.is_empty() && o.len() <= max_size && o.len() <= data.len() => {
            data[..o.len()].copy_from_slice(&o);
            o.len()
        }
        _ => libfuzzer_sys::fuzzer_mutate(data, size, max_size),
    }
}

/// libFuzzer's byte-level mutation of `bytes`, growing to at most `max` bytes.
fn byte_mutate(bytes: &[u8], max: usize) -> Option<Vec<u8>> {
    let max = max.max(bytes.len()).max(1);
    let mut buf = vec![0u8; max];
    buf[..bytes.len()].copy_from_slice(bytes);
    let n = libfuzzer_sys::fuzzer_mutate(&mut buf, bytes.len(), max);
    buf.truncate(n);
    Some(buf)
}

fn json_bytes(doc: &Doc, max_size: usize) -> Option<Vec<u8>> {
    let whole = doc.to_bytes();
    if doc.text {
        return byte_mutate(&whole, max_size);
    }
    let (j, bin) = split_glb(&whole)?;
    let budget = max_size.saturating_sub(bin.as_ref().map_or(0, Vec::len) + 40);
    let j = byte_mutate(&j, budget)?;
    Some(join_glb(&j, bin.as_deref()))
}

/// libFuzzer's mutation of a window of the binary chunk, same length.
fn bin_window(doc: &mut Doc, rng: &mut Rng) -> Option<()> {
    let bin = doc.bin.as_mut().filter(|b| !b.is_empty())?;
    let w = 1 + rng.below(64.min(bin.len()));
    let at = rng.below(bin.len() - w + 1);
    let new = byte_mutate(&bin[at..at + w], w)?;
    let n = new.len().min(w);
    bin[at..at + n].copy_from_slice(&new[..n]);
    Some(())
}

// ---------------------------------------------------------------------------------------------
// Values

/// A value to write into a field, interpreted by the field's [`Kind`].
#[derive(Clone, Copy, Debug)]
enum Val {
    Index(u16),
    Enum(u8),
    Len,
    Zero,
    One,
    MinusOne,
    Plus(u8),
    Minus(u8),
    Double,
    Halve,
    Pow2(u8),
    Pow2Less(u8),
    U32Max,
    U32Wrap,
    I32Min,
    U64Over,
    Big,
    Tiny,
    Inf,
    NegInf,
    NaN,
    NegZero,
    Frac,
    Bits(u32),
    Str,
    Null,
    True,
    EmptyArr,
    EmptyObj,
}

impl<'a> Arbitrary<'a> for Val {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        let k: u8 = u.arbitrary()?;
        Ok(match k {
            0..=49 => Val::Index(u.arbitrary()?),
            50..=69 => Val::Enum(u.arbitrary()?),
            70..=79 => Val::Len,
            80..=99 => Val::Plus(u.arbitrary()?),
            100..=119 => Val::Minus(u.arbitrary()?),
            120..=129 => Val::Zero,
            130..=137 => Val::One,
            138..=143 => Val::MinusOne,
            144..=149 => Val::Double,
            150..=155 => Val::Halve,
            156..=163 => Val::Pow2(u.arbitrary()?),
            164..=169 => Val::Pow2Less(u.arbitrary()?),
            170..=174 => Val::U32Max,
            175..=179 => Val::U32Wrap,
            180..=183 => Val::I32Min,
            184..=186 => Val::U64Over,
            187..=191 => Val::Big,
            192..=195 => Val::Tiny,
            196..=199 => Val::Inf,
            200..=202 => Val::NegInf,
            203..=204 => Val::NaN,
            205..=207 => Val::NegZero,
            208..=213 => Val::Frac,
            214..=229 => Val::Bits(u.arbitrary()?),
            230..=234 => Val::Str,
            235..=239 => Val::Null,
            240..=243 => Val::True,
            244..=248 => Val::EmptyArr,
            249..=251 => Val::EmptyObj,
            _ => Val::Index(u.arbitrary()?),
        })
    }
}

/// What a field holds.
#[derive(Clone, Copy, Debug)]
enum Kind {
    /// Index into a top-level array.
    Ref(&'static str),
    /// Index into an array of the same element (an animation's samplers).
    LocalRef(&'static str),
    /// Array of indices into a top-level array (children, joints, scene nodes).
    RefList(&'static str),
    Int,
    Float,
    /// Float array with this default.
    Floats(&'static [f64]),
    /// One of these raw JSON tokens.
    Enum(&'static [&'static str]),
    Bool,
    Any,
}

const COMPONENT_TYPES: &[&str] = &[
    "5120", "5121", "5122", "5123", "5125", "5126", "5124", "0", "5127", "5130",
];
const TYPES: &[&str] = &[
    "\"SCALAR\"",
    "\"VEC2\"",
    "\"VEC3\"",
    "\"VEC4\"",
    "\"MAT2\"",
    "\"MAT3\"",
    "\"MAT4\"",
    "\"VEC5\"",
    "\"scalar\"",
];
const MODES: &[&str] = &["0", "1", "2", "3", "4", "5", "6", "7"];
const PATHS: &[&str] = &[
    "\"translation\"",
    "\"rotation\"",
    "\"scale\"",
    "\"weights\"",
    "\"matrix\"",
    "\"\"",
];
const INTERPOLATIONS: &[&str] = &["\"LINEAR\"", "\"STEP\"", "\"CUBICSPLINE\"", "\"linear\""];
const ALPHA_MODES: &[&str] = &["\"OPAQUE\"", "\"MASK\"", "\"BLEND\"", "\"mask\""];
const MIME_TYPES: &[&str] = &[
    "\"image/png\"",
    "\"image/jpeg\"",
    "\"image/webp\"",
    "\"image/ktx2\"",
    "\"text/plain\"",
];
const TARGETS: &[&str] = &["34962", "34963", "0", "1"];
const BUFFER_URIS: &[&str] = &[
    "\"buffer.bin\"",
    "\"sub/inner.bin\"",
    "\"sub/../buffer.bin\"",
    "\"%62uffer.bin\"",
    "\"missing.bin\"",
    "\"../buffer.bin\"",
    "\"/etc/hostname\"",
    "\"escape.bin\"",
    "\"sub\"",
    "\"http://example.invalid/a.bin\"",
    "\"data:application/octet-stream;base64,AAAAAAAAgD8AAABA\"",
    "\"data:application/octet-stream;base64,!!\"",
    "\"data:,plain\"",
    "\"\"",
    "\"%\"",
    "\"%zz%2\"",
];
const IMAGE_URIS: &[&str] = &[
    "\"image.png\"",
    "\"buffer.bin\"",
    "\"missing.png\"",
    "\"../image.png\"",
    "\"/etc/hostname\"",
    "\"escape.bin\"",
    "\"data:image/png;base64,iVBORw0KGgo=\"",
    "\"data:image/png;base64,\"",
    "\"file:///etc/hostname\"",
    "\"C:\\\\x.png\"",
];
const NAMES: &[&str] = &[
    "\"leaves\"",
    "\"leaf\"",
    "\"Leaf_Card\"",
    "\"needles\"",
    "\"foliage\"",
    "\"bark\"",
    "\"trunk\"",
    "\"wood\"",
    "\"branch\"",
    "\"\"",
    "\"\\u0000\"",
    "\"leaves bark\"",
];
const EXTENSION_NAMES: &[&str] = &[
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_texture_basisu",
    "KHR_materials_variants",
    "",
    "khr_mesh_quantization",
];

const IDENTITY16: &[f64] = &[
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

struct Field {
    path: &'static str,
    kind: Kind,
}

const fn f(path: &'static str, kind: Kind) -> Field {
    Field { path, kind }
}

/// The fields each top-level array's elements have ("" is the root object); `*` picks an
/// element of a nested array.
const TABLE: &[(&str, &[Field])] = &[
    (
        "accessors",
        &[
            f("bufferView", Kind::Ref("bufferViews")),
            f("byteOffset", Kind::Int),
            f("componentType", Kind::Enum(COMPONENT_TYPES)),
            f("normalized", Kind::Bool),
            f("count", Kind::Int),
            f("count", Kind::Int),
            f("type", Kind::Enum(TYPES)),
            f("min", Kind::Floats(&[0.0, 0.0, 0.0])),
            f("max", Kind::Floats(&[1.0, 1.0, 1.0])),
            f("sparse.count", Kind::Int),
            f("sparse.indices.bufferView", Kind::Ref("bufferViews")),
            f("sparse.indices.byteOffset", Kind::Int),
            f("sparse.indices.componentType", Kind::Enum(COMPONENT_TYPES)),
            f("sparse.values.bufferView", Kind::Ref("bufferViews")),
            f("sparse.values.byteOffset", Kind::Int),
        ],
    ),
    (
        "bufferViews",
        &[
            f("buffer", Kind::Ref("buffers")),
            f("byteOffset", Kind::Int),
            f("byteLength", Kind::Int),
            f("byteStride", Kind::Int),
            f("byteStride", Kind::Int),
            f("target", Kind::Enum(TARGETS)),
        ],
    ),
    (
        "buffers",
        &[
            f("byteLength", Kind::Int),
            f("uri", Kind::Enum(BUFFER_URIS)),
        ],
    ),
    (
        "nodes",
        &[
            f("children", Kind::RefList("nodes")),
            f("mesh", Kind::Ref("meshes")),
            f("skin", Kind::Ref("skins")),
            f("matrix", Kind::Floats(IDENTITY16)),
            f("translation", Kind::Floats(&[0.0, 0.0, 0.0])),
            f("rotation", Kind::Floats(&[0.0, 0.0, 0.0, 1.0])),
            f("scale", Kind::Floats(&[1.0, 1.0, 1.0])),
            f("weights", Kind::Floats(&[0.0])),
            f("name", Kind::Enum(NAMES)),
            f("extras", Kind::Any),
        ],
    ),
    (
        "skins",
        &[
            f("joints", Kind::RefList("nodes")),
            f("joints", Kind::RefList("nodes")),
            f("inverseBindMatrices", Kind::Ref("accessors")),
            f("skeleton", Kind::Ref("nodes")),
        ],
    ),
    (
        "meshes",
        &[
            f("primitives.*.attributes.POSITION", Kind::Ref("accessors")),
            f("primitives.*.attributes.NORMAL", Kind::Ref("accessors")),
            f("primitives.*.attributes.TEXCOORD_0", Kind::Ref("accessors")),
            f("primitives.*.attributes.TEXCOORD_1", Kind::Ref("accessors")),
            f("primitives.*.attributes.JOINTS_0", Kind::Ref("accessors")),
            f("primitives.*.attributes.WEIGHTS_0", Kind::Ref("accessors")),
            f("primitives.*.indices", Kind::Ref("accessors")),
            f("primitives.*.indices", Kind::Ref("accessors")),
            f("primitives.*.mode", Kind::Enum(MODES)),
            f("primitives.*.material", Kind::Ref("materials")),
            f("primitives.*.targets", Kind::Any),
            f("name", Kind::Enum(NAMES)),
        ],
    ),
    (
        "animations",
        &[
            f("channels.*.sampler", Kind::LocalRef("samplers")),
            f("channels.*.target.node", Kind::Ref("nodes")),
            f("channels.*.target.path", Kind::Enum(PATHS)),
            f("samplers.*.input", Kind::Ref("accessors")),
            f("samplers.*.input", Kind::Ref("accessors")),
            f("samplers.*.output", Kind::Ref("accessors")),
            f("samplers.*.interpolation", Kind::Enum(INTERPOLATIONS)),
            f("name", Kind::Enum(NAMES)),
        ],
    ),
    (
        "materials",
        &[
            f(
                "pbrMetallicRoughness.baseColorTexture.index",
                Kind::Ref("textures"),
            ),
            f("pbrMetallicRoughness.baseColorTexture.texCoord", Kind::Int),
            f(
                "pbrMetallicRoughness.baseColorFactor",
                Kind::Floats(&[1.0, 1.0, 1.0, 1.0]),
            ),
            f("alphaMode", Kind::Enum(ALPHA_MODES)),
            f("alphaCutoff", Kind::Float),
            f("doubleSided", Kind::Bool),
            f("name", Kind::Enum(NAMES)),
            f(
                "pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.offset",
                Kind::Floats(&[0.0, 0.0]),
            ),
            f(
                "pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.rotation",
                Kind::Float,
            ),
            f(
                "pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.scale",
                Kind::Floats(&[1.0, 1.0]),
            ),
            f(
                "pbrMetallicRoughness.baseColorTexture.extensions.KHR_texture_transform.texCoord",
                Kind::Int,
            ),
        ],
    ),
    (
        "textures",
        &[
            f("source", Kind::Ref("images")),
            f("source", Kind::Ref("images")),
            f("sampler", Kind::Ref("samplers")),
        ],
    ),
    (
        "images",
        &[
            f("bufferView", Kind::Ref("bufferViews")),
            f("uri", Kind::Enum(IMAGE_URIS)),
            f("mimeType", Kind::Enum(MIME_TYPES)),
        ],
    ),
    (
        "samplers",
        &[f("magFilter", Kind::Int), f("wrapS", Kind::Int)],
    ),
    ("scenes", &[f("nodes", Kind::RefList("nodes"))]),
    (
        "",
        &[
            f("scene", Kind::Ref("scenes")),
            f(
                "asset.version",
                Kind::Enum(&["\"2.0\"", "\"1.0\"", "\"3.0\"", "2"]),
            ),
            f("asset", Kind::Any),
            f("accessors", Kind::Any),
            f("bufferViews", Kind::Any),
            f("nodes", Kind::Any),
            f("extensionsUsed", Kind::Any),
        ],
    ),
];

fn delta(k: u8) -> f64 {
    if k < 200 {
        1.0 + (k % 4) as f64
    } else {
        (k as f64) * 97.0
    }
}

/// The value `v` means for a scalar field of `kind` whose current value is `cur`.
fn scalar(doc: &mut Doc, kind: Kind, v: Val, cur: Option<&Value>, ref_len: Option<usize>) -> Value {
    let c = cur.and_then(Value::as_f64).unwrap_or(0.0);
    let int = !matches!(kind, Kind::Float | Kind::Floats(_));
    let num = |x: f64| {
        if int && x.fract() == 0.0 && x.abs() < 9e15 {
            json!(x as i64)
        } else {
            json!(x)
        }
    };
    let pick = |doc: &mut Doc, i: usize| -> Value {
        match (kind, ref_len) {
            (Kind::Enum(list), _) => doc.raw(list[i % list.len()]),
            (Kind::Bool, _) => json!(i.is_multiple_of(2)),
            (_, Some(0)) => json!(0),
            (_, Some(l)) => json!(i % l),
            _ if int => json!(i % 64),
            _ => json!((i % 256) as f64 / 16.0 - 8.0),
        }
    };
    match v {
        Val::Index(i) => pick(doc, i as usize),
        Val::Enum(i) => pick(doc, i as usize),
        Val::Len => json!(ref_len.unwrap_or((c.max(0.0) as usize).saturating_add(1))),
        Val::Zero => json!(0),
        Val::One => json!(1),
        Val::MinusOne => json!(-1),
        Val::Plus(k) => num(c + delta(k)),
        Val::Minus(k) => num(c - delta(k)),
        Val::Double => num(if c == 0.0 { 1.0 } else { c * 2.0 }),
        Val::Halve => num(if int { (c / 2.0).floor() } else { c / 2.0 }),
        Val::Pow2(k) => json!(1u64 << (k % 64)),
        Val::Pow2Less(k) => json!((1u64 << (k % 64)).saturating_sub(1).max(1)),
        Val::U32Max => json!(u32::MAX),
        Val::U32Wrap => json!(1u64 << 32),
        Val::I32Min => json!(i32::MIN),
        Val::U64Over => doc.raw("18446744073709551616"),
        Val::Big => doc.raw("3.4e38"),
        Val::Tiny => doc.raw("1e-45"),
        Val::Inf => doc.raw("1e999"),
        Val::NegInf => doc.raw("-1e999"),
        Val::NaN => doc.raw("NaN"),
        Val::NegZero => doc.raw("-0.0"),
        Val::Frac => json!(c + 0.5),
        Val::Bits(b) => {
            let x = f32::from_bits(b);
            if x.is_finite() {
                json!(x as f64)
            } else {
                doc.raw("1e39")
            }
        }
        Val::Str => json!(format!("{c}")),
        Val::Null => Value::Null,
        Val::True => json!(true),
        Val::EmptyArr => json!([]),
        Val::EmptyObj => json!({}),
    }
}

/// The new value of a field of `kind` (arrays edited element-wise).
fn field_value(
    doc: &mut Doc,
    kind: Kind,
    v: Val,
    cur: Option<&Value>,
    ref_len: Option<usize>,
    sub: usize,
) -> Value {
    let (elem_kind, default): (Kind, &[f64]) = match kind {
        Kind::RefList(a) => (Kind::Ref(a), &[]),
        Kind::Floats(d) => (Kind::Float, d),
        _ => return scalar(doc, kind, v, cur, ref_len),
    };
    let mut a: Vec<Value> = match cur {
        Some(Value::Array(a)) => a.clone(),
        _ => default.iter().map(|x| json!(x)).collect(),
    };
    match v {
        Val::EmptyArr | Val::EmptyObj | Val::Null | Val::Str | Val::True => {
            return scalar(doc, kind, v, cur, ref_len);
        }
        Val::Len => a.push(match kind {
            Kind::RefList(_) => json!(ref_len.unwrap_or(0)),
            _ => json!(0.0),
        }),
        Val::Minus(k) if k % 2 == 0 && !a.is_empty() => {
            a.remove(sub % a.len());
        }
        Val::Double if !a.is_empty() => {
            let x = a[sub % a.len()].clone();
            a.push(x);
        }
        Val::Index(i) if i % 2 == 0 && matches!(kind, Kind::RefList(_)) => {
            a.push(json!(ref_len.map_or(0, |l| i as usize % l.max(1))));
        }
        _ => {
            if a.is_empty() {
                let x = scalar(doc, elem_kind, v, None, ref_len);
                a.push(x);
            } else {
                let i = sub % a.len();
                let old = a[i].clone();
                a[i] = scalar(doc, elem_kind, v, Some(&old), ref_len);
            }
        }
    }
    Value::Array(a)
}

// ---------------------------------------------------------------------------------------------
// JSON paths

enum Seg {
    Key(String),
    Idx(usize),
}

/// Resolves `path` ('.'-separated, `*` = element `subs[k] % len`) below `base`; None when a
/// `*` meets a missing or empty array.
fn resolve(base: &Value, path: &str, subs: &[u16]) -> Option<Vec<Seg>> {
    let mut out = Vec::new();
    let mut cur = Some(base);
    let mut k = 0;
    for part in path.split('.') {
        if part == "*" {
            let arr = cur?.as_array().filter(|a| !a.is_empty())?;
            let i = subs.get(k).copied().unwrap_or(0) as usize % arr.len();
            k += 1;
            cur = arr.get(i);
            out.push(Seg::Idx(i));
        } else {
            cur = cur.and_then(|c| c.get(part));
            out.push(Seg::Key(part.to_string()));
        }
    }
    Some(out)
}

fn get<'a>(base: &'a Value, segs: &[Seg]) -> Option<&'a Value> {
    let mut cur = base;
    for s in segs {
        cur = match s {
            Seg::Key(k) => cur.get(k)?,
            Seg::Idx(i) => cur.get(*i)?,
        };
    }
    Some(cur)
}

/// Sets (or, for None, removes) the value at `segs`, creating missing objects on the way.
fn put(base: &mut Value, segs: &[Seg], v: Option<Value>) -> Option<()> {
    let (last, init) = segs.split_last()?;
    let mut cur = base;
    for s in init {
        cur = match s {
            Seg::Key(k) => {
                let obj = cur.as_object_mut()?;
                let e = obj.entry(k.clone()).or_insert_with(|| json!({}));
                if !(e.is_object() || e.is_array()) {
                    *e = json!({});
                }
                e
            }
            Seg::Idx(i) => cur.get_mut(*i)?,
        };
    }
    match (last, v) {
        (Seg::Key(k), Some(v)) => {
            cur.as_object_mut()?.insert(k.clone(), v);
        }
        (Seg::Key(k), None) => {
            cur.as_object_mut()?.remove(k);
        }
        (Seg::Idx(i), Some(v)) => *cur.get_mut(*i)? = v,
        (Seg::Idx(i), None) => {
            let a = cur.as_array_mut()?;
            if *i < a.len() {
                a.remove(*i);
            }
        }
    }
    Some(())
}

/// JSON pointers of every value in the document (up to a bound), for the generic edits.
fn locations(v: &Value, prefix: &mut String, out: &mut Vec<String>) {
    if out.len() >= 100_000 {
        return;
    }
    let len = prefix.len();
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                prefix.push('/');
                prefix.push_str(&k.replace('~', "~0").replace('/', "~1"));
                out.push(prefix.clone());
                locations(c, prefix, out);
                prefix.truncate(len);
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                prefix.push('/');
                prefix.push_str(&i.to_string());
                out.push(prefix.clone());
                locations(c, prefix, out);
                prefix.truncate(len);
            }
        }
        _ => {}
    }
}

fn all_locations(doc: &Doc) -> Vec<String> {
    let mut out = Vec::new();
    locations(&doc.json, &mut String::new(), &mut out);
    out
}

fn remove_pointer(root: &mut Value, ptr: &str) -> Option<()> {
    let cut = ptr.rfind('/')?;
    let (parent, last) = (&ptr[..cut], &ptr[cut + 1..]);
    let last = last.replace("~1", "/").replace("~0", "~");
    match root.pointer_mut(parent)? {
        Value::Object(m) => {
            m.remove(&last);
        }
        Value::Array(a) => {
            let i: usize = last.parse().ok()?;
            if i < a.len() {
                a.remove(i);
            }
        }
        _ => return None,
    }
    Some(())
}

/// Element `i` of top-level array `arr`, if it is an object.
fn object_at<'a>(root: &'a mut Value, arr: &str, i: usize) -> Option<&'a mut Map<String, Value>> {
    root.get_mut(arr)?.get_mut(i)?.as_object_mut()
}

// ---------------------------------------------------------------------------------------------
// Binary-chunk helpers

/// Where accessor `a`'s elements live in the binary chunk: (base, stride, component size,
/// component type, width, count).
fn accessor_layout(doc: &Doc, a: usize) -> Option<(usize, usize, usize, u64, usize, usize)> {
    let acc = doc.json.get("accessors")?.get(a)?;
    let comp = acc.get("componentType")?.as_u64()?;
    let csize = match comp {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        _ => return None,
    };
    let width = match acc.get("type")?.as_str()? {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    };
    let count = acc.get("count")?.as_u64()? as usize;
    let view = doc
        .json
        .get("bufferViews")?
        .get(acc.get("bufferView")?.as_u64()? as usize)?;
    if view.get("buffer").and_then(Value::as_u64) != Some(0) {
        return None;
    }
    let base = (view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize)
        .checked_add(acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize)?;
    let stride = match view.get("byteStride").and_then(Value::as_u64) {
        Some(s) if s > 0 => s as usize,
        _ => width * csize,
    };
    Some((base, stride, csize, comp, width, count))
}

#[derive(Arbitrary, Clone, Copy, Debug)]
enum BinVal {
    NaN,
    Inf,
    NegInf,
    Zero,
    NegZero,
    One,
    MinusOne,
    Big,
    Denormal,
    Max,
    Plus1,
    Minus1,
    CopyPrev,
    SwapNext,
    Bits(u32),
}

fn bin_write(doc: &mut Doc, a: usize, e: u32, c: u8, v: BinVal) -> Option<()> {
    let (base, stride, csize, comp, width, count) = accessor_layout(doc, a)?;
    if count == 0 {
        return None;
    }
    let e = e as usize % count;
    let c = c as usize % width;
    let bin = doc.bin.as_mut()?;
    let limit = bin.len();
    let at = |e: usize| -> Option<usize> {
        let p = e
            .checked_mul(stride)?
            .checked_add(base)?
            .checked_add(c * csize)?;
        (p.checked_add(csize)? <= limit).then_some(p)
    };
    let pos = at(e)?;
    match v {
        BinVal::CopyPrev if e > 0 => {
            let p = at(e - 1)?;
            let prev = bin[p..p + csize].to_vec();
            bin[pos..pos + csize].copy_from_slice(&prev);
            return Some(());
        }
        BinVal::SwapNext if e + 1 < count => {
            let (s, n) = (pos - c * csize, at(e + 1)? - c * csize);
            let w = width * csize;
            if n + w > bin.len() || s + w > n {
                return None;
            }
            for k in 0..w {
                bin.swap(s + k, n + k);
            }
            return Some(());
        }
        _ => {}
    }
    let bytes: Vec<u8> = if comp == 5126 {
        let old = f32::from_le_bytes(bin[pos..pos + 4].try_into().ok()?);
        let x = match v {
            BinVal::NaN => f32::NAN,
            BinVal::Inf => f32::INFINITY,
            BinVal::NegInf => f32::NEG_INFINITY,
            BinVal::Zero => 0.0,
            BinVal::NegZero => -0.0,
            BinVal::One => 1.0,
            BinVal::MinusOne => -1.0,
            BinVal::Big => 3.0e38,
            BinVal::Denormal => 1e-40,
            BinVal::Max => f32::MAX,
            BinVal::Plus1 => old + 1.0,
            BinVal::Minus1 => old - 1.0,
            BinVal::Bits(b) => f32::from_bits(b),
            BinVal::CopyPrev | BinVal::SwapNext => -old,
        };
        x.to_le_bytes().to_vec()
    } else {
        let mut old = 0u64;
        for k in 0..csize {
            old |= (bin[pos + k] as u64) << (8 * k);
        }
        let max = (1u64 << (8 * csize)) - 1;
        let x = match v {
            BinVal::Zero | BinVal::NegZero => 0,
            BinVal::One => 1,
            BinVal::Max | BinVal::NaN | BinVal::Inf | BinVal::MinusOne => max,
            BinVal::Big | BinVal::NegInf => max - 1,
            BinVal::Plus1 => old.wrapping_add(1) & max,
            BinVal::Minus1 => old.wrapping_sub(1) & max,
            BinVal::Denormal => max / 2 + 1,
            BinVal::Bits(b) => b as u64 & max,
            BinVal::CopyPrev | BinVal::SwapNext => old ^ 1,
        };
        (0..csize).map(|k| (x >> (8 * k)) as u8).collect()
    };
    bin[pos..pos + csize].copy_from_slice(&bytes);
    Some(())
}

#[derive(Arbitrary, Clone, Copy, Debug)]
enum TimePattern {
    AllEqual,
    Reverse,
    Negate,
    Scale(u8),
    Shift(i8),
    NaNAt(u16),
    InfLast,
    Denormal,
    Zeros,
    OneKeyCount,
    ZeroKeyCount,
}

fn key_times(doc: &mut Doc, which: u16, p: TimePattern) -> Option<()> {
    let mut inputs: Vec<usize> = Vec::new();
    for a in doc.json.get("animations")?.as_array()? {
        for s in a
            .get("samplers")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if let Some(i) = s.get("input").and_then(Value::as_u64) {
                inputs.push(i as usize);
            }
        }
    }
    if inputs.is_empty() {
        return None;
    }
    let acc = inputs[which as usize % inputs.len()];
    match p {
        TimePattern::OneKeyCount | TimePattern::ZeroKeyCount => {
            let n = if matches!(p, TimePattern::OneKeyCount) {
                1
            } else {
                0
            };
            object_at(&mut doc.json, "accessors", acc)?.insert("count".into(), json!(n));
            return Some(());
        }
        _ => {}
    }
    let (base, stride, _, comp, width, count) = accessor_layout(doc, acc)?;
    if comp != 5126 || width != 1 || count == 0 {
        return None;
    }
    let bin = doc.bin.as_mut()?;
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(base))
        .and_then(|x| x.checked_add(4));
    if end.is_none_or(|e| e > bin.len()) {
        return None;
    }
    let read = |bin: &[u8], k: usize| {
        f32::from_le_bytes(
            bin[base + k * stride..base + k * stride + 4]
                .try_into()
                .unwrap(),
        )
    };
    let mut t: Vec<f32> = (0..count).map(|k| read(bin, k)).collect();
    match p {
        TimePattern::AllEqual => t.iter_mut().for_each(|x| *x = 1.0),
        TimePattern::Reverse => t.reverse(),
        TimePattern::Negate => t.iter_mut().for_each(|x| *x = -*x),
        TimePattern::Scale(k) => {
            let s = 10f32.powi((k % 80) as i32 - 40);
            t.iter_mut().for_each(|x| *x *= s);
        }
        TimePattern::Shift(k) => {
            let s = 10f32.powi((k % 40) as i32);
            t.iter_mut().for_each(|x| *x += s);
        }
        TimePattern::NaNAt(i) => t[i as usize % count] = f32::NAN,
        TimePattern::InfLast => t[count - 1] = f32::INFINITY,
        TimePattern::Denormal => t
            .iter_mut()
            .enumerate()
            .for_each(|(i, x)| *x = f32::from_bits(i as u32)),
        TimePattern::Zeros => t.iter_mut().for_each(|x| *x = 0.0),
        TimePattern::OneKeyCount | TimePattern::ZeroKeyCount => {}
    }
    for (k, x) in t.iter().enumerate() {
        bin[base + k * stride..base + k * stride + 4].copy_from_slice(&x.to_le_bytes());
    }
    Some(())
}

// ---------------------------------------------------------------------------------------------
// Images

#[derive(Arbitrary, Clone, Copy, Debug)]
enum ImageKind {
    Png { w: u8, h: u8, seed: u32 },
    Jpeg { w: u8, h: u8 },
    Gray { w: u8, h: u8 },
    HugeHeader { w: u16, h: u16 },
    Truncated(u16),
    Garbage(u16),
    Empty,
    Gif,
    DataUri { w: u8, h: u8 },
    External(u8),
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG whose header claims `w × h` RGBA pixels but whose data is one empty stored block.
fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut chunk = |ty: &[u8], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = ty.to_vec();
        c.extend_from_slice(data);
        out.extend_from_slice(&c);
        out.extend_from_slice(&crc32(&c).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(
        b"IDAT",
        &[0x78, 0x01, 0x01, 0x00, 0x00, 0xFF, 0xFF, 0, 0, 0, 1],
    );
    chunk(b"IEND", &[]);
    out
}

fn encode(img: image::DynamicImage, format: image::ImageFormat) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    let _ = img.write_to(&mut out, format);
    out.into_inner()
}

fn image_op(doc: &mut Doc, which: u16, kind: ImageKind) -> Option<()> {
    let dims = |w: u8, h: u8| (1 + (w % 16) as u32, 1 + (h % 16) as u32);
    // An image to replace: an existing one, or a new one wired to material 0.
    let n = doc.len_of("images");
    let img = if n > 0 {
        which as usize % n
    } else {
        doc.array_mut("images")
            .push(json!({ "mimeType": "image/png" }));
        doc.array_mut("textures").push(json!({ "source": 0 }));
        let t = doc.len_of("textures") - 1;
        if let Some(m) = object_at(&mut doc.json, "materials", 0) {
            let pbr = m.entry("pbrMetallicRoughness").or_insert_with(|| json!({}));
            if let Some(pbr) = pbr.as_object_mut() {
                pbr.insert("baseColorTexture".into(), json!({ "index": t }));
            }
        }
        0
    };
    let bytes: Vec<u8> = match kind {
        ImageKind::Png { w, h, seed } => {
            let (w, h) = dims(w, h);
            tiny_png(w, h, seed)
        }
        ImageKind::Jpeg { w, h } => {
            let (w, h) = dims(w, h);
            let rgb =
                image::RgbImage::from_fn(w, h, |x, y| image::Rgb([x as u8 * 9, y as u8 * 9, 77]));
            encode(
                image::DynamicImage::ImageRgb8(rgb),
                image::ImageFormat::Jpeg,
            )
        }
        ImageKind::Gray { w, h } => {
            let (w, h) = dims(w, h);
            let g = image::GrayImage::from_fn(w, h, |x, y| image::Luma([(x * 16 + y) as u8]));
            encode(image::DynamicImage::ImageLuma8(g), image::ImageFormat::Png)
        }
        ImageKind::HugeHeader { w, h } => png_header_only(1 + w as u32 * 4, 1 + h as u32 * 4),
        ImageKind::Truncated(k) => {
            let p = tiny_png(4, 4, 1);
            let cut = k as usize % p.len();
            p[..cut].to_vec()
        }
        ImageKind::Garbage(k) => (0..(k % 512)).map(|i| (i * 31) as u8).collect(),
        ImageKind::Empty => Vec::new(),
        ImageKind::Gif => b"GIF89a\x01\x00\x01\x00\x00\x00\x00;".to_vec(),
        ImageKind::DataUri { w, h } => {
            let (w, h) = dims(w, h);
            let b64 = base64::engine::general_purpose::STANDARD.encode(tiny_png(w, h, 3));
            let im = &mut doc.array_mut("images")[img];
            if let Some(o) = im.as_object_mut() {
                o.remove("bufferView");
                o.insert("uri".into(), json!(format!("data:image/png;base64,{b64}")));
            }
            return Some(());
        }
        ImageKind::External(k) => {
            let uri = IMAGE_URIS[k as usize % IMAGE_URIS.len()];
            let uri: Value = serde_json::from_str(uri).ok()?;
            let im = &mut doc.array_mut("images")[img];
            if let Some(o) = im.as_object_mut() {
                o.remove("bufferView");
                o.insert("uri".into(), uri);
            }
            return Some(());
        }
    };
    let view = doc.append_view(&bytes)?;
    let im = &mut doc.array_mut("images")[img];
    let o = im.as_object_mut()?;
    o.remove("uri");
    o.insert("bufferView".into(), json!(view));
    Some(())
}

// ---------------------------------------------------------------------------------------------
// Hierarchy, skins, sparse

#[derive(Arbitrary, Clone, Copy, Debug)]
enum ChildHow {
    SelfLoop,
    Cycle,
    SecondParent,
    OutOfRange(u8),
    Duplicate,
    Reparent,
    Detach,
}

fn parent_of(doc: &Doc, n: usize) -> Option<usize> {
    doc.json.get("nodes")?.as_array()?.iter().position(|p| {
        p.get("children")
            .and_then(Value::as_array)
            .is_some_and(|c| c.iter().any(|x| x.as_u64() == Some(n as u64)))
    })
}

fn push_child(doc: &mut Doc, parent: usize, child: Value) -> Option<()> {
    let node = doc
        .json
        .get_mut("nodes")?
        .get_mut(parent)?
        .as_object_mut()?;
    let c = node.entry("children").or_insert_with(|| json!([]));
    if !c.is_array() {
        *c = json!([]);
    }
    c.as_array_mut()?.push(child);
    Some(())
}

fn unlink(doc: &mut Doc, child: usize) -> Option<()> {
    let p = parent_of(doc, child)?;
    let c = object_at(&mut doc.json, "nodes", p)?
        .get_mut("children")?
        .as_array_mut()?;
    c.retain(|x| x.as_u64() != Some(child as u64));
    Some(())
}

fn child_op(doc: &mut Doc, a: u16, b: u16, how: ChildHow) -> Option<()> {
    let n = doc.len_of("nodes");
    if n == 0 {
        return None;
    }
    let (a, b) = (a as usize % n, b as usize % n);
    match how {
        ChildHow::SelfLoop => push_child(doc, a, json!(a)),
        ChildHow::Cycle => {
            // Make `a` a child of its own deepest first-child descendant.
            let mut d = a;
            for _ in 0..64 {
                match doc.json["nodes"][d]["children"]
                    .get(0)
                    .and_then(Value::as_u64)
                {
                    Some(c) if (c as usize) < n && c as usize != a => d = c as usize,
                    _ => break,
                }
            }
            push_child(doc, d, json!(a))
        }
        ChildHow::SecondParent => push_child(doc, a, json!(b)),
        ChildHow::OutOfRange(k) => push_child(
            doc,
            a,
            match k % 3 {
                0 => json!(n),
                1 => json!(n + 1000),
                _ => json!(u32::MAX),
            },
        ),
        ChildHow::Duplicate => {
            let c = doc.json["nodes"][a]["children"].get(0).cloned()?;
            push_child(doc, a, c)
        }
        ChildHow::Reparent => {
            let _ = unlink(doc, b);
            push_child(doc, a, json!(b))
        }
        ChildHow::Detach => unlink(doc, b),
    }
}

/// Appends a chain of `depth` new nodes below node `at` (or as a scene root), the last one
/// carrying a mesh (and skin) of an existing node; optionally making the chain skin joints.
fn deep_chain(doc: &mut Doc, at: u16, depth: usize, as_joints: bool) -> Option<()> {
    let n = doc.len_of("nodes");
    let carrier = doc
        .json
        .get("nodes")?
        .as_array()?
        .iter()
        .find(|x| x.get("mesh").is_some())
        .cloned();
    {
        let nodes = doc.array_mut("nodes");
        for k in 0..depth {
            let mut node = Map::new();
            if k + 1 < depth {
                node.insert("children".into(), json!([n + k + 1]));
            } else if let Some(c) = &carrier {
                node.insert("mesh".into(), c["mesh"].clone());
                if let Some(s) = c.get("skin") {
                    node.insert("skin".into(), s.clone());
                }
            }
            node.insert("translation".into(), json!([0.0, 0.01, 0.0]));
            nodes.push(Value::Object(node));
        }
    }
    if n > 0 {
        push_child(doc, at as usize % n, json!(n))?;
    } else if let Some(s) = object_at(&mut doc.json, "scenes", 0) {
        s.insert("nodes".into(), json!([n]));
    }
    if as_joints
        && let Some(j) = doc
            .json
            .get_mut("skins")
            .and_then(|s| s.get_mut(0))
            .and_then(|s| s.get_mut("joints"))
            .and_then(Value::as_array_mut)
    {
        j.extend(
            (n..n + depth)
                .step_by((depth / 64).max(1))
                .map(|i| json!(i)),
        );
    }
    Some(())
}

/// Adds root nodes that all instance mesh `mesh` (each instance is flattened into its own
/// vertices by the importer, so this multiplies the vertex count).
fn instance_op(doc: &mut Doc, mesh: u16, k: u16, budget: usize) -> Option<()> {
    let nm = doc.len_of("meshes");
    if nm == 0 {
        return None;
    }
    let cap = (budget / 40).clamp(1, 50_000);
    let k = match k % 3 {
        0 => 1 + k as usize % 8,
        1 => 1 + k as usize % 512,
        _ => 1 + k as usize,
    }
    .min(cap);
    let m = mesh as usize % nm;
    let nodes = doc.array_mut("nodes");
    nodes.extend((0..k).map(|i| json!({ "mesh": m, "translation": [i as f64 * 0.5, 0.0, 0.0] })));
    Some(())
}

#[derive(Arbitrary, Clone, Copy, Debug)]
enum JointsHow {
    Push(u16),
    PushOutOfRange,
    Remove(u16),
    Clear,
    Reverse,
    Many(u16),
    DropInverseBind,
}

fn joints_op(doc: &mut Doc, skin: u16, how: JointsHow, budget: usize) -> Option<()> {
    let ns = doc.len_of("skins");
    let nn = doc.len_of("nodes");
    if ns == 0 {
        return None;
    }
    let skin = doc.json.get_mut("skins")?.get_mut(skin as usize % ns)?;
    if let JointsHow::DropInverseBind = how {
        skin.as_object_mut()?.remove("inverseBindMatrices");
        return Some(());
    }
    let j = skin.get_mut("joints")?.as_array_mut()?;
    match how {
        JointsHow::Push(i) => j.push(json!(i as usize % nn.max(1))),
        JointsHow::PushOutOfRange => j.push(json!(nn)),
        JointsHow::Remove(i) if !j.is_empty() => {
            j.remove(i as usize % j.len());
        }
        JointsHow::Clear => j.clear(),
        JointsHow::Reverse => j.reverse(),
        JointsHow::Many(k) => {
            let m = (k as usize).min(budget / 6).min(70_000);
            j.extend((0..m).map(|i| json!(i % nn.max(1))));
        }
        _ => return None,
    }
    Some(())
}

fn sparse_op(doc: &mut Doc, a: u16, count: u8, comp: u8, seed: u32) -> Option<()> {
    let na = doc.len_of("accessors");
    if na == 0 {
        return None;
    }
    let a = a as usize % na;
    let acc_count = doc.json["accessors"][a]["count"].as_u64().unwrap_or(0) as usize;
    let width = match doc.json["accessors"][a]["type"].as_str() {
        Some("VEC2") => 2,
        Some("VEC3") => 3,
        Some("VEC4") | Some("MAT2") => 4,
        Some("MAT4") => 16,
        _ => 1,
    };
    let k = 1 + count as usize % 8;
    // Indices mostly inside the accessor, ascending; sometimes one past its end.
    let mut idx: Vec<u32> = (0..k)
        .map(|i| {
            let span = acc_count.max(1) as u64;
            ((seed as u64).wrapping_mul(i as u64 + 1) % (span + (comp / 4 % 2) as u64)) as u32
        })
        .collect();
    idx.sort_unstable();
    let (ctype, ibytes): (u32, Vec<u8>) = match comp % 3 {
        0 => (5121, idx.iter().map(|&i| i as u8).collect()),
        1 => (
            5123,
            idx.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
        ),
        _ => (5125, idx.iter().flat_map(|&i| i.to_le_bytes()).collect()),
    };
    let vals: Vec<u8> = (0..k * width)
        .flat_map(|i| ((i as f32) * 0.5 - 1.0).to_le_bytes())
        .collect();
    let iv = doc.append_view(&ibytes)?;
    let vv = doc.append_view(&vals)?;
    object_at(&mut doc.json, "accessors", a)?.insert(
        "sparse".into(),
        json!({
            "count": k,
            "indices": { "bufferView": iv, "byteOffset": 0, "componentType": ctype },
            "values": { "bufferView": vv, "byteOffset": 0 },
        }),
    );
    Some(())
}

fn view_op(doc: &mut Doc, v: u16, off: u32, len: u32, stride: u8) -> Option<()> {
    let nv = doc.len_of("bufferViews");
    if nv == 0 {
        return None;
    }
    let bl = doc.bin.as_ref().map_or(0, Vec::len) + 16;
    let view = object_at(&mut doc.json, "bufferViews", v as usize % nv)?;
    match stride % 4 {
        0 => {
            view.insert("byteOffset".into(), json!(off as usize % bl));
        }
        1 => {
            view.insert("byteLength".into(), json!(len as usize % bl));
        }
        2 => {
            const S: &[u64] = &[0, 1, 2, 3, 4, 6, 8, 12, 16, 20, 24, 28, 32, 252, 255, 256];
            view.insert("byteStride".into(), json!(S[(off as usize) % S.len()]));
        }
        _ => {
            view.remove("byteStride");
            view.insert("byteOffset".into(), json!(off as usize % bl));
            view.insert("byteLength".into(), json!(len as usize % bl));
        }
    }
    Some(())
}

const ATTRIBUTE_NAMES: &[&str] = &[
    "POSITION",
    "NORMAL",
    "TEXCOORD_0",
    "TEXCOORD_1",
    "TEXCOORD_2",
    "JOINTS_0",
    "WEIGHTS_0",
    "JOINTS_1",
    "WEIGHTS_1",
    "COLOR_0",
    "TANGENT",
    "_CUSTOM",
    "position",
    "TEXCOORD_4294967296",
];

fn rename_attribute(doc: &mut Doc, m: u16, p: u16, a: u8, to: u8) -> Option<()> {
    let nm = doc.len_of("meshes");
    if nm == 0 {
        return None;
    }
    let prims = object_at(&mut doc.json, "meshes", m as usize % nm)?
        .get_mut("primitives")?
        .as_array_mut()?;
    if prims.is_empty() {
        return None;
    }
    let np = prims.len();
    let attrs = prims[p as usize % np]
        .get_mut("attributes")?
        .as_object_mut()?;
    let keys: Vec<String> = attrs.keys().cloned().collect();
    if keys.is_empty() {
        return None;
    }
    let from = &keys[a as usize % keys.len()];
    let v = attrs.remove(from)?;
    attrs.insert(
        ATTRIBUTE_NAMES[to as usize % ATTRIBUTE_NAMES.len()].into(),
        v,
    );
    Some(())
}

// ---------------------------------------------------------------------------------------------
// The structured edit

fn field_op(doc: &mut Doc, u: &mut Unstructured, delete: bool) -> Option<()> {
    let (arr, fields) = TABLE[u.choose_index(TABLE.len()).ok()?];
    let field = &fields[u.choose_index(fields.len()).ok()?];
    let subs: [u16; 2] = u.arbitrary().ok()?;
    let elem: u16 = u.arbitrary().ok()?;
    let base_segs: Vec<Seg> = if arr.is_empty() {
        Vec::new()
    } else {
        let n = doc.len_of(arr);
        if n == 0 {
            return None;
        }
        vec![Seg::Key(arr.into()), Seg::Idx(elem as usize % n)]
    };
    let base = get(&doc.json, &base_segs)?;
    let mut segs = base_segs;
    segs.extend(resolve(base, field.path, &subs)?);
    if delete {
        return put(&mut doc.json, &segs, None);
    }
    let ref_len = match field.kind {
        Kind::Ref(a) | Kind::RefList(a) => Some(doc.len_of(a)),
        Kind::LocalRef(k) => Some(
            get(&doc.json, &segs[..2.min(segs.len())])
                .and_then(|e| e.get(k))
                .and_then(Value::as_array)
                .map_or(0, Vec::len),
        ),
        _ => None,
    };
    let cur = get(&doc.json, &segs).cloned();
    let v: Val = u.arbitrary().ok()?;
    let sub: u16 = u.arbitrary().ok()?;
    let new = field_value(doc, field.kind, v, cur.as_ref(), ref_len, sub as usize);
    put(&mut doc.json, &segs, Some(new))
}

fn generic_op(doc: &mut Doc, u: &mut Unstructured, what: u8) -> Option<()> {
    let locs = all_locations(doc);
    if locs.is_empty() {
        return None;
    }
    let a = &locs[u.choose_index(locs.len()).ok()?];
    match what % 4 {
        0 | 1 => {
            let cur = doc.json.pointer(a).cloned();
            let v: Val = u.arbitrary().ok()?;
            let new = scalar(doc, Kind::Any, v, cur.as_ref(), None);
            *doc.json.pointer_mut(a)? = new;
            Some(())
        }
        2 => remove_pointer(&mut doc.json, a),
        _ => {
            let b = &locs[u.choose_index(locs.len()).ok()?];
            let v = doc.json.pointer(a)?.clone();
            *doc.json.pointer_mut(b)? = v;
            Some(())
        }
    }
}

fn array_op(doc: &mut Doc, u: &mut Unstructured) -> Option<()> {
    let arrays: Vec<String> = all_locations(doc)
        .into_iter()
        .filter(|p| {
            doc.json
                .pointer(p)
                .and_then(Value::as_array)
                .is_some_and(|a| !a.is_empty())
        })
        .collect();
    if arrays.is_empty() {
        return None;
    }
    let p = &arrays[u.choose_index(arrays.len()).ok()?];
    let how: u8 = u.arbitrary().ok()?;
    let (i, j): (u16, u16) = u.arbitrary().ok()?;
    let a = doc.json.pointer_mut(p)?.as_array_mut()?;
    let (i, j) = (i as usize % a.len(), j as usize % a.len());
    match how % 4 {
        0 => {
            let x = a[i].clone();
            a.push(x);
        }
        1 => {
            let x = a[i].clone();
            a.insert(j, x);
        }
        2 => {
            a.remove(i);
        }
        _ => a.swap(i, j),
    }
    Some(())
}

fn extension_op(doc: &mut Doc, which: u8, required: bool) -> Option<()> {
    let name = EXTENSION_NAMES[which as usize % EXTENSION_NAMES.len()];
    doc.array_mut("extensionsUsed").push(json!(name));
    if required {
        doc.array_mut("extensionsRequired").push(json!(name));
    }
    Some(())
}

/// Applies one to four structured edits; `budget` is how many bytes the input may grow.
fn structured(doc: &mut Doc, u: &mut Unstructured, budget: usize) -> Option<()> {
    let n = match u.arbitrary::<u8>().ok()? {
        0..=127 => 1,
        128..=199 => 2,
        200..=239 => 3,
        _ => 4,
    };
    let mut done = 0;
    for _ in 0..n * 3 {
        if done == n {
            break;
        }
        let k: u8 = u.arbitrary().ok()?;
        let r = match k % 100 {
            0..=29 => field_op(doc, u, false),
            30..=33 => field_op(doc, u, true),
            34..=43 => {
                let w: u8 = u.arbitrary().ok()?;
                generic_op(doc, u, w)
            }
            44..=48 => array_op(doc, u),
            49..=53 => {
                let (a, b, how): (u16, u16, ChildHow) = u.arbitrary().ok()?;
                child_op(doc, a, b, how)
            }
            54..=55 => {
                let (at, d, j): (u16, u16, bool) = u.arbitrary().ok()?;
                let cap = (budget / 48).clamp(1, 20_000);
                let depth = match d % 4 {
                    0 => 1 + d as usize % 8,
                    1 => 64 + d as usize % 64,
                    _ => 1 + d as usize % cap,
                };
                deep_chain(doc, at, depth.min(cap), j)
            }
            56..=59 => {
                let (s, how): (u16, JointsHow) = u.arbitrary().ok()?;
                joints_op(doc, s, how, budget)
            }
            60..=71 => {
                let (a, e, c, v): (u16, u32, u8, BinVal) = u.arbitrary().ok()?;
                let na = doc.len_of("accessors");
                bin_write(doc, a as usize % na.max(1), e, c, v)
            }
            72..=76 => {
                let (w, p): (u16, TimePattern) = u.arbitrary().ok()?;
                key_times(doc, w, p)
            }
            77..=81 => {
                let (w, kind): (u16, ImageKind) = u.arbitrary().ok()?;
                image_op(doc, w, kind)
            }
            82..=84 => {
                let (a, c, t, s): (u16, u8, u8, u32) = u.arbitrary().ok()?;
                sparse_op(doc, a, c, t, s)
            }
            85..=86 => {
                let (w, r): (u8, bool) = u.arbitrary().ok()?;
                extension_op(doc, w, r)
            }
            87 => {
                let (m, k): (u16, u16) = u.arbitrary().ok()?;
                instance_op(doc, m, k, budget)
            }
            88..=94 => {
                let (v, o, l, s): (u16, u32, u32, u8) = u.arbitrary().ok()?;
                view_op(doc, v, o, l, s)
            }
            _ => {
                let (m, p, a, t): (u16, u16, u8, u8) = u.arbitrary().ok()?;
                rename_attribute(doc, m, p, a, t)
            }
        };
        if r.is_some() {
            done += 1;
        }
    }
    (done > 0).then_some(())
}

// ---------------------------------------------------------------------------------------------
// Container edits

#[derive(Arbitrary, Clone, Copy, Debug)]
enum ContainerOp {
    Truncate(u32),
    TotalLength(u8),
    JsonLength(u8),
    BinLength(u8),
    Version(u8),
    BinChunkType,
    DropBin,
    ExtraChunk(u8),
    JsonNulPad,
    Bom,
    TrailingGarbage(u8),
    ToText,
    ToTextExternal,
    ToGlb,
}

fn edge_len(actual: usize, k: u8) -> u32 {
    match k % 9 {
        0 => 0,
        1 => 1,
        2 => actual.saturating_sub(1) as u32,
        3 => actual as u32 + 1,
        4 => actual as u32 + 4,
        5 => u32::MAX,
        6 => (actual as u32).wrapping_mul(2),
        7 => 12,
        _ => 20,
    }
}

fn container(doc: &mut Doc, u: &mut Unstructured) -> Option<Vec<u8>> {
    let op: ContainerOp = u.arbitrary().ok()?;
    match op {
        ContainerOp::ToText if !doc.text => {
            if let Some(bin) = doc.bin.take() {
                let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
                let buffers = doc.array_mut("buffers");
                if let Some(b) = buffers.get_mut(0).and_then(Value::as_object_mut) {
                    b.insert(
                        "uri".into(),
                        json!(format!("data:application/octet-stream;base64,{b64}")),
                    );
                }
            }
            doc.text = true;
            return Some(doc.to_bytes());
        }
        ContainerOp::ToTextExternal if !doc.text => {
            doc.bin = None;
            if let Some(b) = doc
                .array_mut("buffers")
                .get_mut(0)
                .and_then(Value::as_object_mut)
            {
                b.insert("uri".into(), json!("buffer.bin"));
                b.insert("byteLength".into(), json!(4096));
            }
            doc.text = true;
            return Some(doc.to_bytes());
        }
        ContainerOp::ToGlb if doc.text => {
            let uri = doc.json["buffers"][0]["uri"].as_str().map(str::to_string);
            if let Some(payload) = uri.as_deref().and_then(|u| u.split_once(";base64,")) {
                doc.bin = base64::engine::general_purpose::STANDARD
                    .decode(payload.1)
                    .ok();
                if let Some(b) = object_at(&mut doc.json, "buffers", 0) {
                    b.remove("uri");
                }
            }
            doc.text = false;
            return Some(doc.to_bytes());
        }
        _ => {}
    }
    let mut b = doc.to_bytes();
    if doc.text {
        return match op {
            ContainerOp::Bom => Some([b"\xEF\xBB\xBF".as_slice(), &b].concat()),
            ContainerOp::Truncate(k) => Some(b[..k as usize % b.len().max(1)].to_vec()),
            ContainerOp::TrailingGarbage(k) => {
                b.extend(std::iter::repeat_n(b'}', 1 + k as usize % 4));
                Some(b)
            }
            _ => None,
        };
    }
    let jl = u32::from_le_bytes(b[12..16].try_into().ok()?) as usize;
    let set = |b: &mut Vec<u8>, at: usize, v: u32| {
        if at + 4 <= b.len() {
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
    };
    match op {
        ContainerOp::Truncate(k) => b.truncate(k as usize % b.len()),
        ContainerOp::TotalLength(k) => {
            let n = b.len();
            set(&mut b, 8, edge_len(n, k));
        }
        ContainerOp::JsonLength(k) => set(&mut b, 12, edge_len(jl, k)),
        ContainerOp::BinLength(k) => {
            let bl = b.len().saturating_sub(28 + jl);
            set(&mut b, 20 + jl, edge_len(bl, k));
        }
        ContainerOp::Version(k) => set(&mut b, 4, [0, 1, 3, u32::MAX][k as usize % 4]),
        ContainerOp::BinChunkType => {
            if b.len() >= 28 + jl {
                b[24 + jl..28 + jl].copy_from_slice(b"BIN\x01");
            }
        }
        ContainerOp::DropBin => {
            b.truncate(20 + jl);
            let n = b.len() as u32;
            set(&mut b, 8, n);
        }
        ContainerOp::ExtraChunk(k) => {
            let len = (k as usize % 5) * 4;
            b.extend_from_slice(&(len as u32).to_le_bytes());
            b.extend_from_slice(if k % 2 == 0 { b"XTRA" } else { b"BIN\0" });
            b.extend(std::iter::repeat_n(0xAB, len));
            let n = b.len() as u32;
            set(&mut b, 8, n);
        }
        ContainerOp::JsonNulPad => {
            // Pad the JSON chunk with NULs instead of spaces (some writers do).
            let json_end = 20 + jl;
            let mut i = json_end;
            while i > 20 && b[i - 1] == b' ' {
                b[i - 1] = 0;
                i -= 1;
            }
        }
        ContainerOp::Bom => {
            let mut j = b"\xEF\xBB\xBF".to_vec();
            j.extend_from_slice(&b[20..20 + jl]);
            let bin = doc.bin.clone();
            return Some(join_glb(&j, bin.as_deref()));
        }
        ContainerOp::TrailingGarbage(k) => {
            b.extend(std::iter::repeat_n(0x5A, 1 + k as usize % 7));
        }
        ContainerOp::ToText | ContainerOp::ToTextExternal | ContainerOp::ToGlb => return None,
    }
    Some(b)
}

// ---------------------------------------------------------------------------------------------
// Crossover

/// libFuzzer's custom crossover: one input's document with a top-level member (or one
/// element of it) taken from the other's; a byte splice when either does not parse. Returns 0
/// (no crossover) for three seeds in four.
pub fn crossover(d1: &[u8], d2: &[u8], out: &mut [u8], seed: u32) -> usize {
    let mut rng = Rng::new(seed as u64 ^ 0xC0FFEE);
    // With a custom mutator and a custom crossover, libFuzzer picks each half of the time;
    // crossover parses two documents, so decline three times in four (libFuzzer then runs
    // the mutator instead).
    if rng.below(4) != 0 {
        return 0;
    }
    let result = match (Doc::parse(d1), Doc::parse(d2)) {
        (Some(mut a), Some(b)) => {
            let keys: Vec<String> = b
                .json
                .as_object()
                .map(|m| m.keys().cloned().collect())
                .unwrap_or_default();
            if keys.is_empty() {
                None
            } else {
                let k = &keys[rng.below(keys.len())];
                let theirs = &b.json[k.as_str()];
                match (a.json.get_mut(k.as_str()), theirs) {
                    (Some(Value::Array(mine)), Value::Array(t))
                        if !t.is_empty() && rng.below(2) == 0 =>
                    {
                        let x = t[rng.below(t.len())].clone();
                        if mine.is_empty() || rng.below(2) == 0 {
                            mine.push(x);
                        } else {
                            let i = rng.below(mine.len());
                            mine[i] = x;
                        }
                    }
                    _ => a.json[k.as_str()] = theirs.clone(),
                }
                Some(a.to_bytes())
            }
        }
        _ => None,
    };
    let bytes = result.unwrap_or_else(|| {
        let i = rng.below(d1.len() + 1);
        let j = rng.below(d2.len() + 1);
        [&d1[..i], &d2[j..]].concat()
    });
    let n = bytes.len().min(out.len());
    out[..n].copy_from_slice(&bytes[..n]);
    n
}

//! Loads a `.glb` / `.gltf` file: its JSON document, its buffers, and (on request) its images.
//! External files are read only from inside the input's own folder, by the rules of
//! [`crate::input_file`].

use std::path::{Path, PathBuf};

use base64::Engine;
use gltf::json;

use crate::error::{Result, SceneError};
use crate::input_file::{InputLimits, ReadRefusal, human_bytes, read_regular_file, resolve_uri};

/// Extensions whose presence in `extensionsRequired` we can honour.
pub const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_mesh_quantization",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_texture_basisu",
    "EXT_meshopt_compression",
];

/// A parsed glTF document with its binary buffers resolved.
pub struct GltfSource {
    /// The file the document came from (used in every error message).
    pub path: PathBuf,
    /// The folder that external resources must stay inside.
    pub dir: PathBuf,
    /// The JSON document.
    pub root: json::Root,
    /// Buffer contents, index-aligned with `root.buffers`.
    pub buffers: Vec<Vec<u8>>,
    /// What reading this input may cost.
    pub limits: InputLimits,
    /// Bytes of input read so far: the file and its external buffers (external images are
    /// added by the importer, which reads them, against the same limit).
    pub bytes_read: u64,
    /// The parts of the document that are passed through unchanged, as raw JSON (the typed
    /// `root` drops what it does not model, such as unknown material extensions).
    pub raw: RawParts,
    /// Per buffer view, its bytes decoded from `EXT_meshopt_compression` (None: stored plainly).
    pub decoded_views: Vec<Option<Vec<u8>>>,
}

/// The input's materials, textures, samplers and images as raw JSON values, index-aligned with
/// the document's arrays (a missing array is empty).
#[derive(Clone, Debug, Default, serde::Deserialize)]
pub struct RawParts {
    /// The `materials` array.
    #[serde(default)]
    pub materials: Vec<serde_json::Value>,
    /// The `textures` array.
    #[serde(default)]
    pub textures: Vec<serde_json::Value>,
    /// The `samplers` array.
    #[serde(default)]
    pub samplers: Vec<serde_json::Value>,
    /// The `images` array.
    #[serde(default)]
    pub images: Vec<serde_json::Value>,
    /// The `buffers` array.
    #[serde(default)]
    pub buffers: Vec<serde_json::Value>,
    /// The `bufferViews` array.
    #[serde(default, rename = "bufferViews")]
    pub buffer_views: Vec<serde_json::Value>,
}

impl GltfSource {
    /// Reads and parses `path`, resolving every buffer, within `limits` (the file and its
    /// external buffers are read by [`crate::input_file`]'s rules).
    pub fn open(path: &Path, limits: &InputLimits) -> Result<Self> {
        let bytes = read_regular_file(path, limits.max_input_bytes).map_err(|r| match r {
            ReadRefusal::Io(error) => SceneError::Io {
                path: path.to_path_buf(),
                error,
            },
            other => SceneError::invalid(path, other.to_string()),
        })?;
        Self::from_bytes(path, &bytes, limits)
    }

    /// Parses `bytes` as if read from `path` (which locates external resources), within
    /// `limits` (`bytes` counts towards the input size).
    pub fn from_bytes(path: &Path, bytes: &[u8], limits: &InputLimits) -> Result<Self> {
        let err = |p: String| SceneError::invalid(path, p);
        let parse = |json_bytes: &[u8]| -> Result<json::Root> {
            serde_json::from_slice(json_bytes)
                .map_err(|e| err(format!("not a valid glTF JSON document ({e})")))
        };
        let parse_raw = |json_bytes: &[u8]| -> Result<RawParts> {
            serde_json::from_slice(json_bytes)
                .map_err(|e| err(format!("not a valid glTF JSON document ({e})")))
        };
        let (root, raw, glb_bin): (json::Root, RawParts, Option<Vec<u8>>) = if bytes
            .starts_with(b"glTF")
        {
            // gltf 1.4 subtracts the header's size from the declared length before checking
            // it (an overflow panic in debug builds): check the 12-byte header first.
            let declared = bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
            match declared {
                Some(n) if (12..=bytes.len()).contains(&n) => {}
                Some(n) => {
                    return Err(err(format!(
                        "truncated or malformed GLB container (the header declares {n} bytes, the file has {})",
                        bytes.len()
                    )));
                }
                None => {
                    return Err(err(
                        "truncated or malformed GLB container (shorter than its 12-byte header)"
                            .into(),
                    ));
                }
            }
            let glb = gltf::binary::Glb::from_slice(bytes)
                .map_err(|e| err(format!("truncated or malformed GLB container ({e})")))?;
            (
                parse(&glb.json)?,
                parse_raw(&glb.json)?,
                glb.bin.map(|b| b.into_owned()),
            )
        } else {
            let first = bytes.iter().find(|b| !b.is_ascii_whitespace()).copied();
            if first != Some(b'{') {
                return Err(err(
                    "not a glTF file (neither GLB magic nor a JSON object)".into()
                ));
            }
            (parse(bytes)?, parse_raw(bytes)?, None)
        };
        for ext in &root.extensions_required {
            if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext.as_str()) {
                return Err(SceneError::UnsupportedExtension {
                    path: path.to_path_buf(),
                    extension: ext.clone(),
                });
            }
        }
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let mut src = GltfSource {
            path: path.to_path_buf(),
            dir,
            root,
            buffers: Vec::new(),
            limits: *limits,
            bytes_read: 0,
            raw,
            decoded_views: Vec::new(),
        };
        let mut total = bytes.len() as u64;
        let mut glb_bin = glb_bin;
        let mut buffers = Vec::with_capacity(src.root.buffers.len());
        for (i, buffer) in src.root.buffers.iter().enumerate() {
            let declared = buffer.byte_length.0 as usize;
            // A meshopt fallback buffer has no data: only compressed views point at it.
            if crate::meshopt_views::is_fallback_buffer(src.raw.buffers.get(i)) {
                buffers.push(Vec::new());
                continue;
            }
            let data = match &buffer.uri {
                None => glb_bin.take().ok_or_else(|| {
                    err(format!(
                        "buffer {i} has no uri and the file has no GLB binary chunk"
                    ))
                })?,
                Some(uri) => src.read_uri(uri, &format!("buffer {i}"))?,
            };
            if buffer.uri.is_some() {
                total = total.saturating_add(data.len() as u64);
                if total > limits.max_input_bytes {
                    return Err(err(format!(
                        "buffer {i}: the file and its external buffers add up to {}, over the input size limit of {} (raise the input size limit to read it)",
                        human_bytes(total),
                        human_bytes(limits.max_input_bytes)
                    )));
                }
            }
            if data.len() < declared {
                return Err(err(format!(
                    "buffer {i} holds {} bytes but declares byteLength {declared} (truncated file?)",
                    data.len()
                )));
            }
            buffers.push(data);
        }
        src.buffers = buffers;
        src.bytes_read = total;
        src.decoded_views = crate::meshopt_views::decode_views(
            &src.raw.buffer_views,
            &src.buffers,
            limits.max_input_bytes,
        )
        .map_err(err)?;
        Ok(src)
    }

    /// An error about this document.
    pub fn invalid(&self, problem: impl Into<String>) -> SceneError {
        SceneError::invalid(&self.path, problem)
    }

    /// Reads a `data:` URI or a relative file inside the input's folder.
    pub fn read_uri(&self, uri: &str, what: &str) -> Result<Vec<u8>> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, payload) = rest
                .split_once(";base64,")
                .ok_or_else(|| self.invalid(format!("{what}: data URI is not base64")))?;
            return base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| self.invalid(format!("{what}: bad base64 data URI ({e})")));
        }
        let full = resolve_uri(&self.dir, uri)
            .map_err(|why| self.invalid(format!("{what}: external URI '{uri}' {why}")))?;
        read_regular_file(&full, self.limits.max_input_bytes)
            .map_err(|r| self.invalid(format!("{what}: '{}' {r}", full.display())))
    }

    /// The encoded bytes of image `index` (from a buffer view, a data URI or a file).
    pub fn image_bytes(&self, index: usize) -> Result<Vec<u8>> {
        let image = self
            .root
            .images
            .get(index)
            .ok_or_else(|| self.invalid(format!("image {index} does not exist")))?;
        let what = format!("image {index}");
        if let Some(view) = image.buffer_view {
            return Ok(self.view_bytes(view.value(), &what)?.to_vec());
        }
        match &image.uri {
            Some(uri) => self.read_uri(uri, &what),
            None => Err(self.invalid(format!("{what} has neither uri nor bufferView"))),
        }
    }

    /// The bytes of buffer view `index`, bounds-checked.
    pub fn view_bytes(&self, index: usize, what: &str) -> Result<&[u8]> {
        if let Some(Some(decoded)) = self.decoded_views.get(index) {
            return Ok(decoded);
        }
        let view =
            self.root.buffer_views.get(index).ok_or_else(|| {
                self.invalid(format!("{what}: bufferView {index} does not exist"))
            })?;
        let buffer = self.buffers.get(view.buffer.value()).ok_or_else(|| {
            self.invalid(format!(
                "{what}: bufferView {index} names buffer {} which does not exist",
                view.buffer.value()
            ))
        })?;
        let start = view.byte_offset.map(|o| o.0).unwrap_or(0) as usize;
        let end = start.checked_add(view.byte_length.0 as usize);
        match end {
            Some(end) if end <= buffer.len() => Ok(&buffer[start..end]),
            _ => Err(self.invalid(format!(
                "{what}: bufferView {index} (offset {start}, length {}) runs past the end of buffer {} ({} bytes)",
                view.byte_length.0,
                view.buffer.value(),
                buffer.len()
            ))),
        }
    }
}

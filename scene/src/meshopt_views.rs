//! `EXT_meshopt_compression` buffer views (what `gltfpack -c`/`-cc` writes): each compressed
//! view names where its meshoptimizer-encoded bytes lie and how to decode them (`mode`:
//! attributes, triangles or an index sequence; `filter`: octahedral normals, quaternions,
//! exponent floats, YCoCg colours), and the view's own buffer may be a fallback without data.
//! Decoded here with meshoptimizer's decoders (the `meshopt` crate's bindings: its typed
//! wrappers want a Rust type per vertex size, a view's stride is any multiple of 4 up to 256),
//! so the rest of the importer reads the views as if they were stored plainly.
//!
//! Written too ([`encode_attributes`], [`encode_triangles`]), for compressed output: the encoders'
//! output in the formats the extension defines (vertex codec version 0, the only one
//! `EXT_meshopt_compression` allows; index codec version 1).

use serde_json::Value;

/// A compressed view's description (the extension object), checked.
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, PartialEq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// Whether buffer `raw` is a fallback buffer of `EXT_meshopt_compression` (no data of its own:
/// only compressed views point at it).
pub fn is_fallback_buffer(raw: Option<&Value>) -> bool {
    raw.and_then(|b| b.pointer("/extensions/EXT_meshopt_compression/fallback"))
        .and_then(Value::as_bool)
        == Some(true)
}

/// Decodes every compressed view of the document (`raw_views`: its `bufferViews` as JSON) from
/// `buffers`: per view, its decoded bytes (`byteLength` of them), None where the view is not
/// compressed. `budget` bounds the decoded bytes in all (a small file must not declare
/// gigabytes). Errors name the view and the problem.
pub fn decode_views(
    raw_views: &[Value],
    buffers: &[Vec<u8>],
    budget: u64,
) -> Result<Vec<Option<Vec<u8>>>, String> {
    let mut total = 0u64;
    raw_views
        .iter()
        .enumerate()
        .map(|(i, view)| {
            let Some(ext) = view.pointer("/extensions/EXT_meshopt_compression") else {
                return Ok(None);
            };
            let c = parse(ext).map_err(|e| format!("bufferView {i}: EXT_meshopt_compression {e}"))?;
            let declared = view.get("byteLength").and_then(Value::as_u64).unwrap_or(0);
            let size = (c.count as u64).saturating_mul(c.stride as u64);
            if size != declared {
                return Err(format!(
                    "bufferView {i}: EXT_meshopt_compression decodes {} × {} = {size} bytes, the view declares {declared}",
                    c.count, c.stride
                ));
            }
            total = total.saturating_add(size);
            if total > budget {
                return Err(format!(
                    "bufferView {i}: compressed views decode to more than the input size limit ({budget} bytes)"
                ));
            }
            let source = buffers
                .get(c.buffer)
                .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
                .ok_or_else(|| {
                    format!(
                        "bufferView {i}: EXT_meshopt_compression data (buffer {}, offset {}, length {}) lies outside its buffer",
                        c.buffer, c.offset, c.length
                    )
                })?;
            decode(&c, source)
                .map(Some)
                .map_err(|e| format!("bufferView {i}: EXT_meshopt_compression {e}"))
        })
        .collect()
}

fn parse(ext: &Value) -> Result<Compressed, String> {
    let num = |k: &str, default: Option<u64>| {
        ext.get(k)
            .and_then(Value::as_u64)
            .or(default)
            .map(|v| v as usize)
            .ok_or_else(|| format!("has no {k}"))
    };
    let mode = match ext.get("mode").and_then(Value::as_str) {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        other => {
            return Err(format!(
                "mode {other:?} is not ATTRIBUTES, TRIANGLES or INDICES"
            ));
        }
    };
    let filter = match ext.get("filter").and_then(Value::as_str) {
        None | Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        Some("COLOR") => Filter::Color,
        Some(f) => return Err(format!("filter {f} is unknown")),
    };
    let c = Compressed {
        buffer: num("buffer", None)?,
        offset: num("byteOffset", Some(0))?,
        length: num("byteLength", None)?,
        stride: num("byteStride", None)?,
        count: num("count", None)?,
        mode,
        filter,
    };
    let stride_ok = match (c.mode, c.filter) {
        (Mode::Attributes, Filter::None | Filter::Exponential) => {
            c.stride.is_multiple_of(4) && (4..=256).contains(&c.stride)
        }
        (Mode::Attributes, Filter::Octahedral | Filter::Color) => c.stride == 4 || c.stride == 8,
        (Mode::Attributes, Filter::Quaternion) => c.stride == 8,
        (_, Filter::None) => c.stride == 2 || c.stride == 4,
        _ => false,
    };
    if !stride_ok {
        return Err(format!(
            "byteStride {} does not fit its mode and filter",
            c.stride
        ));
    }
    if c.mode == Mode::Triangles && !c.count.is_multiple_of(3) {
        return Err(format!(
            "TRIANGLES count {} is not a multiple of 3",
            c.count
        ));
    }
    Ok(c)
}

/// Decodes one view's bytes.
fn decode(c: &Compressed, source: &[u8]) -> Result<Vec<u8>, String> {
    use meshopt::ffi;
    let mut out = vec![0u8; c.count * c.stride];
    // SAFETY: `out` holds count × stride bytes, what each decoder writes for (count, stride);
    // the strides were checked against what each decoder accepts (`parse`); the decoders are
    // safe for untrusted input (they may produce garbage, never write past the destination).
    let code = unsafe {
        match c.mode {
            Mode::Attributes => ffi::meshopt_decodeVertexBuffer(
                out.as_mut_ptr().cast(),
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Triangles => ffi::meshopt_decodeIndexBuffer(
                out.as_mut_ptr().cast(),
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Indices => ffi::meshopt_decodeIndexSequence(
                out.as_mut_ptr().cast(),
                c.count,
                c.stride,
                source.as_ptr(),
                source.len(),
            ),
        }
    };
    if code != 0 {
        return Err(format!("data does not decode (meshoptimizer error {code})"));
    }
    // SAFETY: as above; each filter rewrites count × stride bytes in place.
    unsafe {
        let (p, n, s) = (out.as_mut_ptr().cast(), c.count, c.stride);
        match c.filter {
            Filter::None => {}
            Filter::Octahedral => ffi::meshopt_decodeFilterOct(p, n, s),
            Filter::Quaternion => ffi::meshopt_decodeFilterQuat(p, n, s),
            Filter::Exponential => ffi::meshopt_decodeFilterExp(p, n, s),
            Filter::Color => ffi::meshopt_decodeFilterColor(p, n, s),
        }
    }
    Ok(out)
}

/// The `ATTRIBUTES`-mode encoding of `count` elements of `stride` bytes (a multiple of 4, at
/// most 256, as the extension requires; `bytes` holds exactly `count · stride`), vertex codec
/// version 0 at meshoptimizer's default level.
pub fn encode_attributes(bytes: &[u8], count: usize, stride: usize) -> Result<Vec<u8>, String> {
    if stride == 0 || !stride.is_multiple_of(4) || stride > 256 || bytes.len() != count * stride {
        return Err(format!(
            "{} bytes are not {count} elements of a stride that is a multiple of 4 up to 256 ({stride})",
            bytes.len()
        ));
    }
    use meshopt::ffi;
    // SAFETY: the bound is what the encoder may write for (count, stride); `bytes` holds
    // count × stride bytes (checked above).
    let written = unsafe {
        let bound = ffi::meshopt_encodeVertexBufferBound(count, stride);
        let mut out = vec![0u8; bound];
        let n = ffi::meshopt_encodeVertexBufferLevel(
            out.as_mut_ptr(),
            out.len(),
            bytes.as_ptr().cast(),
            count,
            stride,
            2,
            0,
        );
        out.truncate(n);
        out
    };
    if written.is_empty() {
        return Err("the vertex encoder wrote nothing".into());
    }
    Ok(written)
}

/// The `TRIANGLES`-mode encoding of a triangle list (`indices.len()` a multiple of 3, every
/// index below `vertex_count`), index codec version 1.
pub fn encode_triangles(indices: &[u32], vertex_count: usize) -> Result<Vec<u8>, String> {
    if !indices.len().is_multiple_of(3) || indices.iter().any(|&i| i as usize >= vertex_count) {
        return Err(format!(
            "{} indices are not a triangle list over {vertex_count} vertices",
            indices.len()
        ));
    }
    let out = meshopt::encode_index_buffer(indices, vertex_count).map_err(|e| e.to_string())?;
    if out.is_empty() {
        return Err("the index encoder wrote nothing".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn attributes_and_indices_round_trip_through_meshoptimizer() {
        let verts: Vec<[f32; 3]> = (0..50).map(|i| [i as f32, (i * i) as f32, 0.5]).collect();
        let enc = meshopt::encode_vertex_buffer(&verts).expect("encodes");
        let idx: Vec<u32> = (0..48).collect();
        let ienc = meshopt::encode_index_buffer(&idx, 50).expect("encodes");
        let mut buf = enc.clone();
        buf.extend_from_slice(&ienc);
        let views = vec![
            json!({"buffer": 1, "byteLength": 600, "byteStride": 12, "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": 0, "byteLength": enc.len(), "byteStride": 12, "count": 50, "mode": "ATTRIBUTES"}}}),
            json!({"buffer": 1, "byteLength": 192, "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": enc.len(), "byteLength": ienc.len(), "byteStride": 4, "count": 48, "mode": "TRIANGLES"}}}),
            json!({"buffer": 0, "byteLength": 4}),
        ];
        let out = decode_views(&views, &[buf, Vec::new()], 1 << 20).expect("decodes");
        let v: Vec<f32> = out[0]
            .as_ref()
            .expect("decoded")
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(v, verts.concat());
        let i: Vec<u32> = out[1]
            .as_ref()
            .expect("decoded")
            .chunks(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        assert_eq!(i, idx);
        assert!(out[2].is_none());
    }

    #[test]
    fn bad_descriptions_are_named() {
        let view = |ext: Value, len: u64| json!({"buffer": 0, "byteLength": len, "extensions": {"EXT_meshopt_compression": ext}});
        let bufs = [vec![0u8; 64]];
        let err = |v: Value| decode_views(&[v], &bufs, 1 << 20).expect_err("refused");
        assert!(err(view(json!({"buffer": 0, "byteLength": 8, "byteStride": 12, "count": 2, "mode": "ATTRIBUTES"}), 25)).contains("declares 25"));
        assert!(err(view(json!({"buffer": 0, "byteLength": 8, "byteStride": 6, "count": 2, "mode": "ATTRIBUTES"}), 12)).contains("byteStride 6"));
        assert!(err(view(json!({"buffer": 0, "byteLength": 99, "byteStride": 4, "count": 2, "mode": "ATTRIBUTES"}), 8)).contains("outside"));
        assert!(
            err(view(
                json!({"buffer": 0, "byteLength": 8, "byteStride": 4, "count": 2, "mode": "FOO"}),
                8
            ))
            .contains("mode")
        );
        assert!(err(view(json!({"buffer": 0, "byteLength": 8, "byteStride": 4, "count": 2, "mode": "ATTRIBUTES"}), 8)).contains("decode"));
        // A declared size over the budget is refused before anything is allocated.
        let big = view(
            json!({"buffer": 0, "byteLength": 8, "byteStride": 256, "count": 1_000_000, "mode": "ATTRIBUTES"}),
            256_000_000,
        );
        assert!(
            decode_views(&[big], &bufs, 1 << 20)
                .expect_err("refused")
                .contains("limit")
        );
    }
}

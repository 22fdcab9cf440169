//! Reads glTF accessors into plain vectors: any component type, `normalized` integers
//! (KHR_mesh_quantization), interleaved strides and sparse substitution, all bounds-checked.

use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

use crate::error::Result;
use crate::gltf_source::GltfSource;

/// Largest element count accepted for an accessor without a bufferView (all zeros plus sparse
/// substitutions): guards against absurd allocations from a malformed count.
const MAX_VIEWLESS_ELEMENTS: usize = 1 << 24;

/// A decoded accessor: `count` elements of `width` components each, row-major.
pub struct Decoded {
    /// Components per element (1 for SCALAR up to 16 for MAT4).
    pub width: usize,
    /// `count × width` values, integers converted (normalized ones scaled to [0, 1] or
    /// [-1, 1]).
    pub values: Vec<f32>,
}

impl Decoded {
    /// Element `i` as a fixed-size array (missing components read 0).
    pub fn get<const N: usize>(&self, i: usize) -> [f32; N] {
        let mut out = [0.0; N];
        let row = &self.values[i * self.width..(i + 1) * self.width];
        for (o, v) in out.iter_mut().zip(row) {
            *o = *v;
        }
        out
    }
    /// Number of elements.
    pub fn count(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }
}

pub(crate) fn component_size(c: ComponentType) -> usize {
    match c {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

pub(crate) fn type_width(t: Type) -> usize {
    match t {
        Type::Scalar => 1,
        Type::Vec2 => 2,
        Type::Vec3 => 3,
        Type::Vec4 | Type::Mat2 => 4,
        Type::Mat3 => 9,
        Type::Mat4 => 16,
    }
}

/// Decodes one component; `normalized` integers map to [0,1] or [-1,1] as glTF specifies.
fn decode(bytes: &[u8], c: ComponentType, normalized: bool) -> f32 {
    match c {
        ComponentType::F32 => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        ComponentType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f32,
        ComponentType::I8 => {
            let v = bytes[0] as i8 as f32;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        ComponentType::U8 => {
            let v = bytes[0] as f32;
            if normalized { v / 255.0 } else { v }
        }
        ComponentType::I16 => {
            let v = i16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        ComponentType::U16 => {
            let v = u16::from_le_bytes([bytes[0], bytes[1]]) as f32;
            if normalized { v / 65535.0 } else { v }
        }
    }
}

/// Exact integer decode for indices and joint ids (f32 would lose u32 precision).
fn decode_int(bytes: &[u8], c: ComponentType) -> Option<u32> {
    Some(match c {
        ComponentType::U8 => bytes[0] as u32,
        ComponentType::U16 => u16::from_le_bytes([bytes[0], bytes[1]]) as u32,
        ComponentType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        _ => return None,
    })
}

/// Strided element reader over one buffer view, bounds-checked up front.
struct Strided<'a> {
    data: &'a [u8],
    offset: usize,
    stride: usize,
}

impl GltfSource {
    fn accessor(&self, index: usize, what: &str) -> Result<&json::Accessor> {
        self.root
            .accessors
            .get(index)
            .ok_or_else(|| self.invalid(format!("{what}: accessor {index} does not exist")))
    }

    fn accessor_layout(
        &self,
        acc: &json::Accessor,
        index: usize,
        what: &str,
    ) -> Result<(ComponentType, usize)> {
        let comp = match acc.component_type {
            Checked::Valid(c) => c.0,
            Checked::Invalid => {
                return Err(self.invalid(format!(
                    "{what}: accessor {index} has an invalid componentType"
                )));
            }
        };
        let width = match acc.type_ {
            Checked::Valid(t) => type_width(t),
            Checked::Invalid => {
                return Err(self.invalid(format!("{what}: accessor {index} has an invalid type")));
            }
        };
        Ok((comp, width))
    }

    /// Prepares strided access to `count` elements of `elem` bytes in `view` at `offset`.
    fn strided(
        &self,
        view_index: usize,
        offset: usize,
        count: usize,
        elem: usize,
        what: &str,
        acc_index: usize,
    ) -> Result<Strided<'_>> {
        let data = self.view_bytes(view_index, what)?;
        let stride = self.root.buffer_views[view_index]
            .byte_stride
            .map(|s| s.0)
            .unwrap_or(elem);
        let stride = if stride == 0 { elem } else { stride };
        if stride < elem {
            return Err(self.invalid(format!(
                "{what}: accessor {acc_index} byteStride {stride} is smaller than its element size {elem}"
            )));
        }
        let needed = if count == 0 {
            0
        } else {
            (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset))
                .and_then(|v| v.checked_add(elem))
                .unwrap_or(usize::MAX)
        };
        if needed > data.len() {
            return Err(self.invalid(format!(
                "{what}: accessor {acc_index} needs {needed} bytes (count {count}) but its bufferView {view_index} holds {} bytes",
                data.len()
            )));
        }
        Ok(Strided {
            data,
            offset,
            stride,
        })
    }

    /// Reads accessor `index` as floats (integers converted, normalized ones scaled).
    pub fn read_floats(&self, index: usize, what: &str) -> Result<Decoded> {
        let acc = self.accessor(index, what)?;
        let (comp, width) = self.accessor_layout(acc, index, what)?;
        let count = acc.count.0 as usize;
        let csize = component_size(comp);
        // Matrix columns are 4-byte aligned in glTF; only mat2/mat3 of 1/2-byte types pad.
        let col_pad = match (acc.type_, csize) {
            (Checked::Valid(Type::Mat2), 1) => 2,
            (Checked::Valid(Type::Mat3), 1) => 1,
            (Checked::Valid(Type::Mat3), 2) => 1,
            _ => 0,
        };
        let rows = match acc.type_ {
            Checked::Valid(Type::Mat2) => 2,
            Checked::Valid(Type::Mat3) => 3,
            _ => width,
        };
        let cols = width / rows;
        let elem = cols * (rows * csize + col_pad * csize);
        let total = count
            .checked_mul(width)
            .ok_or_else(|| self.invalid(format!("{what}: accessor {index} count overflows")))?;
        let mut values;
        if let Some(view) = acc.buffer_view {
            let offset = acc.byte_offset.map(|o| o.0).unwrap_or(0) as usize;
            // Bounds are checked before anything is allocated.
            let s = self.strided(view.value(), offset, count, elem, what, index)?;
            values = vec![0.0f32; total];
            for (i, out) in values.chunks_exact_mut(width).enumerate() {
                let base = s.offset + i * s.stride;
                for c in 0..cols {
                    for r in 0..rows {
                        let at = base + c * (rows + col_pad) * csize + r * csize;
                        out[c * rows + r] = decode(&s.data[at..at + csize], comp, acc.normalized);
                    }
                }
            }
        } else {
            if count > MAX_VIEWLESS_ELEMENTS {
                return Err(self.invalid(format!(
                    "{what}: accessor {index} has no bufferView but claims {count} elements"
                )));
            }
            values = vec![0.0f32; total];
        }
        if let Some(sparse) = &acc.sparse {
            self.apply_sparse(
                sparse,
                &mut values,
                width,
                comp,
                acc.normalized,
                count,
                what,
                index,
            )?;
        }
        Ok(Decoded { width, values })
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "a sparse block is defined by that many glTF fields, passed as they are read"
    )]
    fn apply_sparse(
        &self,
        sparse: &json::accessor::sparse::Sparse,
        values: &mut [f32],
        width: usize,
        comp: ComponentType,
        normalized: bool,
        count: usize,
        what: &str,
        index: usize,
    ) -> Result<()> {
        let n = sparse.count.0 as usize;
        let icomp = match sparse.indices.component_type {
            Checked::Valid(c) => c.0,
            Checked::Invalid => {
                return Err(self.invalid(format!(
                    "{what}: accessor {index} sparse indices have an invalid componentType"
                )));
            }
        };
        let isize_ = component_size(icomp);
        let idx = self.strided(
            sparse.indices.buffer_view.value(),
            sparse.indices.byte_offset.0 as usize,
            n,
            isize_,
            what,
            index,
        )?;
        let csize = component_size(comp);
        let vals = self.strided(
            sparse.values.buffer_view.value(),
            sparse.values.byte_offset.0 as usize,
            n,
            width * csize,
            what,
            index,
        )?;
        for k in 0..n {
            // Sparse views are tightly packed (no byteStride allowed).
            let at = idx.offset + k * isize_;
            let target = decode_int(&idx.data[at..at + isize_], icomp).unwrap_or(u32::MAX) as usize;
            if target >= count {
                return Err(self.invalid(format!(
                    "{what}: accessor {index} sparse index {target} is out of range (count {count})"
                )));
            }
            for c in 0..width {
                let at = vals.offset + k * width * csize + c * csize;
                values[target * width + c] = decode(&vals.data[at..at + csize], comp, normalized);
            }
        }
        Ok(())
    }

    /// Reads an integer accessor (indices, joint ids) exactly.
    pub fn read_ints(&self, index: usize, what: &str) -> Result<(usize, Vec<u32>)> {
        let acc = self.accessor(index, what)?;
        let (comp, width) = self.accessor_layout(acc, index, what)?;
        if !matches!(
            comp,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        ) {
            return Err(self.invalid(format!(
                "{what}: accessor {index} must hold unsigned integers, not {comp:?}"
            )));
        }
        if acc.sparse.is_some() {
            // Rare for integer data; decode through floats (exact below 2^24).
            let d = self.read_floats(index, what)?;
            return Ok((width, d.values.iter().map(|v| *v as u32).collect()));
        }
        let count = acc.count.0 as usize;
        let csize = component_size(comp);
        let Some(view) = acc.buffer_view else {
            return Err(self.invalid(format!("{what}: accessor {index} has no bufferView")));
        };
        let offset = acc.byte_offset.map(|o| o.0).unwrap_or(0) as usize;
        let s = self.strided(view.value(), offset, count, width * csize, what, index)?;
        let mut out = vec![0u32; count * width];
        for (i, o) in out.chunks_exact_mut(width).enumerate() {
            let base = s.offset + i * s.stride;
            for (c, v) in o.iter_mut().enumerate() {
                let at = base + c * csize;
                *v = decode_int(&s.data[at..at + csize], comp).unwrap_or(0);
            }
        }
        Ok((width, out))
    }
}

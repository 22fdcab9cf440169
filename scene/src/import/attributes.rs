//! A primitive's vertex attributes, looked up by semantic and read so that each holds one
//! element per vertex (as many as POSITION).

use gltf::json;
use gltf::json::validation::Checked;

use crate::accessor::Decoded;
use crate::error::Result;
use crate::gltf_source::GltfSource;

/// The accessor index of primitive `p`'s attribute `sem`, if it has one.
pub(super) fn attribute(p: &json::mesh::Primitive, sem: json::mesh::Semantic) -> Option<usize> {
    p.attributes.get(&Checked::Valid(sem)).map(|a| a.value())
}

/// A primitive whose POSITION has been read: what the other attributes are read against.
pub(super) struct PrimitiveAttributes<'a> {
    /// The file the primitive is in.
    pub(super) src: &'a GltfSource,
    /// The primitive's JSON (attributes, indices, material, mode).
    pub(super) primitive: &'a json::mesh::Primitive,
    /// The primitive in messages: `mesh 'name' primitive i`.
    pub(super) what: &'a str,
    /// Its vertex count, POSITION's element count: every other attribute must have as many.
    pub(super) n: usize,
}

impl PrimitiveAttributes<'_> {
    /// The accessor index of attribute `sem`, if the primitive has it.
    pub(super) fn accessor(&self, sem: json::mesh::Semantic) -> Option<usize> {
        attribute(self.primitive, sem)
    }

    /// Reads attribute accessor `a` (called `name` in messages) as floats, refusing it unless it
    /// holds one element per vertex.
    pub(super) fn read_counted(&self, a: usize, name: &str) -> Result<Decoded> {
        let d = self.src.read_floats(a, &format!("{} {name}", self.what))?;
        if d.count() != self.n {
            return Err(self.src.invalid(format!(
                "{}: {name} has {} elements, POSITION has {}",
                self.what,
                d.count(),
                self.n
            )));
        }
        Ok(d)
    }

    /// Attribute `sem` (called `name`) read by [`Self::read_counted`], or None when the
    /// primitive has none.
    pub(super) fn optional(
        &self,
        sem: json::mesh::Semantic,
        name: &str,
    ) -> Result<Option<Decoded>> {
        match self.accessor(sem) {
            Some(a) => self.read_counted(a, name).map(Some),
            None => Ok(None),
        }
    }
}

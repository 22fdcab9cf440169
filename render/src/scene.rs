//! Draw inputs: plain triangle meshes, glTF-like materials and RGBA8 textures.

use frond_scene::Wrap;
use glam::Vec3;

use crate::error::RenderError;

/// An RGBA8 texture, sRGB-encoded colour with straight (non-premultiplied) alpha,
/// rows top to bottom.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawTexture {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes.
    pub rgba: Vec<u8>,
}

impl DrawTexture {
    /// A 1×1 clear texture standing in for one a render does not read, so that a scene keeps
    /// its materials' texture indices without a copy of every texture (a tree's bark maps are
    /// most of its texels, and its foliage is often drawn alone).
    pub fn placeholder() -> Self {
        DrawTexture {
            width: 1,
            height: 1,
            rgba: vec![0; 4],
        }
    }
}

/// How a material's alpha is drawn (glTF `alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DrawAlpha {
    /// Alpha is ignored: every fragment covers its sample (glTF OPAQUE).
    Opaque,
    /// Alpha test: fragments with alpha below the cutoff are discarded (glTF MASK).
    Mask(f32),
    /// Alpha blending (glTF BLEND): a fragment of alpha α covers α of its sample, and layers
    /// composite as `1 − Π(1 − αᵢ)`, whatever their order. The CPU coverage rasteriser draws
    /// it so, with plain box-filtered mips (a texel's alpha is a covered fraction, whose area
    /// average is the covered fraction of the larger texel), and so does the wgpu path's
    /// colour render (after the rest, no depth written); renders that cannot blend (the bake,
    /// normal renders) test it at ½ ([`DrawAlpha::test_cutoff`]).
    Blend,
}

impl DrawAlpha {
    /// The alpha test of a renderer that draws every surface opaque or alpha-tested: a MASK
    /// material's cutoff, ½ for BLEND (the coverage a blended texel of alpha ½ or more rounds
    /// to), none for OPAQUE.
    pub fn test_cutoff(self) -> Option<f32> {
        match self {
            DrawAlpha::Opaque => None,
            DrawAlpha::Mask(cutoff) => Some(cutoff),
            DrawAlpha::Blend => Some(0.5),
        }
    }

    /// The alpha test's cutoff of a MASK material; none for OPAQUE and BLEND.
    pub fn mask_cutoff(self) -> Option<f32> {
        match self {
            DrawAlpha::Mask(cutoff) => Some(cutoff),
            DrawAlpha::Opaque | DrawAlpha::Blend => None,
        }
    }
}

/// A metallic-roughness-free subset of a glTF material: base colour, optional base
/// colour texture, alpha mode (OPAQUE, MASK or BLEND) and culling.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawMaterial {
    /// Linear RGBA factor multiplied with the texture sample.
    pub base_color: [f32; 4],
    /// Index into [`DrawScene::textures`], sampled with the mesh's UVs.
    pub texture: Option<usize>,
    /// Index into [`DrawScene::textures`]: a tangent-space normal map (glTF `normalTexture`:
    /// linear RGB, +Y along the mesh's bitangent), applied by the CPU rasteriser to meshes with
    /// [`DrawMesh::tangents`] and sampled with the same UVs as `texture`.
    pub normal_texture: Option<usize>,
    /// How alpha is drawn: ignored, tested or blended.
    pub alpha: DrawAlpha,
    /// Draw both faces; otherwise back faces (clockwise on screen) are culled.
    pub double_sided: bool,
    /// How the texture wraps outside [0, 1] along u and v (the glTF sampler's modes).
    pub wrap: [Wrap; 2],
}

impl DrawMaterial {
    /// An untextured, opaque, single-sided material of the given linear colour.
    pub fn opaque(base_color: [f32; 4]) -> Self {
        Self {
            base_color,
            texture: None,
            normal_texture: None,
            alpha: DrawAlpha::Opaque,
            double_sided: false,
            wrap: [Wrap::Repeat; 2],
        }
    }
}

impl Default for DrawMaterial {
    /// White, untextured, opaque, single-sided (the glTF default material).
    fn default() -> Self {
        Self::opaque([1.0; 4])
    }
}

/// One triangle mesh with per-vertex attributes in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawMesh {
    /// World-space vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex normals; `None` renders the mesh unlit.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per-vertex tangents (xyz, w the bitangent's sign: `B = w · N × T`, glTF `TANGENT`), for
    /// the material's normal map; ignored without normals.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// Per-vertex texture coordinates (glTF convention: v = 0 is the top row).
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangle list, three indices per triangle, counter-clockwise front faces.
    pub indices: Vec<u32>,
    /// Index into [`DrawScene::materials`].
    pub material: usize,
}

/// Everything one render draws: meshes plus the materials and textures they refer to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawScene {
    /// Meshes, drawn in order (the depth test makes the order irrelevant for opaque
    /// and alpha-tested surfaces).
    pub meshes: Vec<DrawMesh>,
    /// Materials referenced by `DrawMesh::material`.
    pub materials: Vec<DrawMaterial>,
    /// Textures referenced by `DrawMaterial::texture`.
    pub textures: Vec<DrawTexture>,
}

impl DrawScene {
    /// Axis-aligned bounds of all finite positions of meshes that have triangles,
    /// or `None` when nothing would be drawn.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut min = Vec3::splat(f32::INFINITY);
        let mut max = Vec3::splat(f32::NEG_INFINITY);
        let mut any = false;
        for mesh in self.meshes.iter().filter(|m| !m.indices.is_empty()) {
            for p in &mesh.positions {
                let p = Vec3::from(*p);
                if p.is_finite() {
                    min = min.min(p);
                    max = max.max(p);
                    any = true;
                }
            }
        }
        any.then_some((min, max))
    }

    /// Checks every index, attribute length, material and texture reference against
    /// `max_texture_dimension`, so rendering never fails halfway on bad input.
    pub fn validate(&self, max_texture_dimension: u32) -> Result<(), RenderError> {
        for (i, mesh) in self.meshes.iter().enumerate() {
            validate_mesh(i, mesh, self.materials.len())?;
        }
        for (i, material) in self.materials.iter().enumerate() {
            if let Some(texture) = material
                .texture
                .into_iter()
                .chain(material.normal_texture)
                .find(|&t| t >= self.textures.len())
            {
                return Err(RenderError::TextureOutOfRange {
                    material: i,
                    texture,
                    count: self.textures.len(),
                });
            }
        }
        for (i, texture) in self.textures.iter().enumerate() {
            validate_texture(i, texture, max_texture_dimension)?;
        }
        Ok(())
    }
}

pub(crate) fn validate_mesh(
    index: usize,
    mesh: &DrawMesh,
    material_count: usize,
) -> Result<(), RenderError> {
    let vertex_count = mesh.positions.len();
    if !mesh.indices.len().is_multiple_of(3) {
        return Err(RenderError::IndexCount {
            mesh: index,
            count: mesh.indices.len(),
        });
    }
    if u32::try_from(vertex_count).is_err() {
        return Err(RenderError::TooManyVertices {
            mesh: index,
            vertex_count,
        });
    }
    let attribute_lengths = [
        ("normals", mesh.normals.as_ref().map(Vec::len)),
        ("uvs", mesh.uvs.as_ref().map(Vec::len)),
        ("tangents", mesh.tangents.as_ref().map(Vec::len)),
    ];
    for (attribute, len) in attribute_lengths {
        if let Some(len) = len
            && len != vertex_count
        {
            return Err(RenderError::AttributeLength {
                mesh: index,
                attribute,
                len,
                expected: vertex_count,
            });
        }
    }
    if let Some(position) = mesh
        .indices
        .iter()
        .position(|&i| i as usize >= vertex_count)
    {
        return Err(RenderError::IndexOutOfRange {
            mesh: index,
            position,
            index: mesh.indices[position],
            vertex_count,
        });
    }
    if !mesh.indices.is_empty() && mesh.material >= material_count {
        return Err(RenderError::MaterialOutOfRange {
            mesh: index,
            material: mesh.material,
            count: material_count,
        });
    }
    Ok(())
}

fn validate_texture(
    index: usize,
    texture: &DrawTexture,
    max_dimension: u32,
) -> Result<(), RenderError> {
    let invalid = |reason: String| RenderError::InvalidTexture {
        texture: index,
        reason,
    };
    if texture.width == 0 || texture.height == 0 {
        return Err(invalid(format!(
            "size {}x{} is empty",
            texture.width, texture.height
        )));
    }
    if texture.width > max_dimension || texture.height > max_dimension {
        return Err(invalid(format!(
            "size {}x{} exceeds the device limit of {max_dimension} pixels per side",
            texture.width, texture.height
        )));
    }
    let expected = u64::from(texture.width) * u64::from(texture.height) * 4;
    if texture.rgba.len() as u64 != expected {
        return Err(invalid(format!(
            "rgba has {} bytes but {}x{}x4 = {expected} are needed",
            texture.rgba.len(),
            texture.width,
            texture.height
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> DrawScene {
        DrawScene {
            meshes: vec![DrawMesh {
                positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                indices: vec![0, 1, 2],
                ..Default::default()
            }],
            materials: vec![DrawMaterial::default()],
            textures: vec![],
        }
    }

    #[test]
    fn valid_scene_passes() {
        assert!(triangle().validate(8192).is_ok());
        assert!(DrawScene::default().validate(8192).is_ok());
    }

    #[test]
    fn bad_inputs_are_reported() {
        let mut s = triangle();
        s.meshes[0].indices = vec![0, 1, 3];
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::IndexOutOfRange { index: 3, .. })
        ));

        let mut s = triangle();
        s.meshes[0].indices = vec![0, 1];
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::IndexCount { .. })
        ));

        let mut s = triangle();
        s.meshes[0].material = 1;
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::MaterialOutOfRange { .. })
        ));

        let mut s = triangle();
        s.meshes[0].uvs = Some(vec![[0.0; 2]]);
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::AttributeLength {
                attribute: "uvs",
                ..
            })
        ));

        let mut s = triangle();
        s.materials[0].texture = Some(0);
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::TextureOutOfRange { .. })
        ));

        let mut s = triangle();
        s.textures.push(DrawTexture {
            width: 2,
            height: 2,
            rgba: vec![0; 15],
        });
        assert!(matches!(
            s.validate(8192),
            Err(RenderError::InvalidTexture { .. })
        ));

        let mut s = triangle();
        s.textures.push(DrawTexture {
            width: 4,
            height: 1,
            rgba: vec![0; 16],
        });
        assert!(matches!(
            s.validate(2),
            Err(RenderError::InvalidTexture { .. })
        ));
    }

    #[test]
    fn bounds_ignore_meshes_without_triangles() {
        let mut s = triangle();
        s.meshes.push(DrawMesh {
            positions: vec![[100.0; 3]],
            ..Default::default()
        });
        let (min, max) = s.bounds().unwrap_or_default();
        assert_eq!(min, Vec3::ZERO);
        assert_eq!(max, Vec3::new(1.0, 1.0, 0.0));
        assert!(DrawScene::default().bounds().is_none());
    }
}

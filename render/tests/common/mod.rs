//! Helpers shared by the render crate's integration tests.

use frond_render::{DrawMesh, Renderer};

/// A renderer on whatever adapter the machine has; fails (never skips) when none exists.
pub fn renderer() -> Renderer {
    match Renderer::new() {
        Ok(r) => {
            eprintln!("adapter: {}", r.adapter_info());
            r
        }
        Err(e) => panic!("no renderer (CI machines have Mesa llvmpipe): {e}"),
    }
}

/// Axis-aligned quad facing +Z at depth `z`, counter-clockwise seen from +Z.
pub fn quad_z(min: [f32; 2], max: [f32; 2], z: f32, material: usize) -> DrawMesh {
    DrawMesh {
        positions: vec![
            [min[0], min[1], z],
            [max[0], min[1], z],
            [max[0], max[1], z],
            [min[0], max[1], z],
        ],
        normals: None,
        tangents: None,
        uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
    }
}

// Each test binary compiles this module on its own and uses only part of it; the unnamed
// constant names every helper once, which rustc's dead-code pass counts as a use (no lint
// exception needed; see tests/common/mod.rs at the workspace root).
const _: () = {
    let _ = (renderer, quad_z);
};

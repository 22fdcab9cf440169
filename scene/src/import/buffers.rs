//! Checks of the file's binary layout that change nothing frond reads but deserve a warning.

use crate::gltf_source::GltfSource;

/// Warns about a bufferView whose `byteStride` is 0: glTF allows 4 to 252, and frond (like
/// most readers) takes 0 as tightly packed, which may not be what the writer meant.
pub(super) fn check_buffer_views(src: &GltfSource, warnings: &mut Vec<String>) {
    for (vi, view) in src.root.buffer_views.iter().enumerate() {
        if view.byte_stride.map(|s| s.0) != Some(0) {
            continue;
        }
        let users: Vec<String> = src
            .root
            .accessors
            .iter()
            .enumerate()
            .filter(|(_, a)| a.buffer_view.map(|v| v.value()) == Some(vi))
            .map(|(a, _)| a.to_string())
            .collect();
        let readers = if users.is_empty() {
            "no accessor reads it".to_string()
        } else {
            format!(
                "accessor{} {} read it as tightly packed",
                if users.len() == 1 { "" } else { "s" },
                users.join(", ")
            )
        };
        warnings.push(format!(
            "bufferView {vi}: byteStride 0 is invalid (glTF allows 4 to 252); {readers}"
        ));
    }
}

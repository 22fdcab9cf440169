//! Binds every foliage triangle to one bone (spec animated-billboard-clouds §1.3): the bone that
//! holds most of its vertices, weighted by skin weight; ties go to the bone nearest the root.

use crate::model::{Part, Tree};

/// The bone a node follows: itself if it is a bone, else its nearest bone ancestor.
pub fn bone_of_node(tree: &Tree, node: usize) -> Option<usize> {
    let mut n = Some(node);
    while let Some(i) = n {
        if let Some(b) = tree.rig.nodes[i].bone {
            return Some(b);
        }
        n = tree.rig.nodes[i].parent;
    }
    None
}

/// Sets `Triangle::bone` for foliage and returns how many triangles were reassigned (their
/// vertices carried weight on some other bone too).
pub fn assign_foliage_bones(tree: &mut Tree) -> usize {
    // Bone of each palette entry of each binding.
    let palette_bones: Vec<Vec<Option<usize>>> = tree
        .bindings
        .iter()
        .map(|b| match b {
            crate::model::Binding::Skin { joints, .. } => joints.iter().map(|&j| Some(j)).collect(),
            crate::model::Binding::Node(n) => vec![bone_of_node(tree, *n)],
        })
        .collect();
    let mut reassigned = 0;
    let v = &tree.vertices;
    let mut bones = Vec::with_capacity(tree.triangles.len());
    for t in &tree.triangles {
        if t.part != Part::Foliage {
            bones.push(None);
            continue;
        }
        // Accumulate weight per bone over the three vertices (at most 12 entries).
        let mut score: Vec<(usize, f32)> = Vec::with_capacity(12);
        for &vi in &t.v {
            let vi = vi as usize;
            let pal = &palette_bones[v.binding[vi] as usize];
            for s in 0..4 {
                let w = v.weights[vi][s];
                if w <= 0.0 {
                    continue;
                }
                if let Some(b) = pal[v.joints[vi][s] as usize] {
                    match score.iter_mut().find(|e| e.0 == b) {
                        Some(e) => e.1 += w,
                        None => score.push((b, w)),
                    }
                }
            }
        }
        let best = score.iter().copied().max_by(|a, b| {
            let tie = (a.1 - b.1).abs() <= 1e-5;
            if tie {
                // Nearer the root wins; then lower index, for determinism.
                tree.bones[b.0]
                    .depth
                    .cmp(&tree.bones[a.0].depth)
                    .then(b.0.cmp(&a.0))
            } else {
                a.1.total_cmp(&b.1)
            }
        });
        if score.len() > 1 {
            reassigned += 1;
        }
        bones.push(best.map(|b| b.0 as u32));
    }
    for (t, b) in tree.triangles.iter_mut().zip(bones) {
        t.bone = b;
    }
    reassigned
}

//! The node hierarchy: rest transforms, parents and children, a parents-first order, and the
//! scenes' root lists checked against it.

use glam::{Mat4, Quat, Vec3};

use crate::error::Result;
use crate::gltf_source::GltfSource;
use crate::rig::{Node, Trs};

/// Deepest node hierarchy accepted, counting a root as level 1. Real tree skeletons are under
/// 30 levels (the shared trees: at most 8 bones in a chain); a chain thousands deep is a
/// malformed or hostile file, and writing it back out crashes glTF tools that walk the
/// hierarchy recursively (the Khronos validator among them). frond's own walks are iterative,
/// so the limit only keeps what frond writes readable.
pub const MAX_NODE_DEPTH: usize = 256;

/// Reads the node hierarchy: rest transforms, parents and children, and a parents-first order.
///
/// Refuses a node with two parents, a cycle, and a hierarchy deeper than [`MAX_NODE_DEPTH`]
/// (naming the first node past the limit). Everything here is iterative, so no depth can
/// overflow the stack before that check.
pub(crate) fn read_nodes(src: &GltfSource) -> Result<(Vec<Node>, Vec<usize>)> {
    let n = src.root.nodes.len();
    let mut nodes = Vec::with_capacity(n);
    for (i, jn) in src.root.nodes.iter().enumerate() {
        let rest = match jn.matrix {
            Some(m) => {
                let m = Mat4::from_cols_array(&m);
                if !m.is_finite() {
                    return Err(src.invalid(format!("node {i} matrix is not finite")));
                }
                let (s, r, t) = m.to_scale_rotation_translation();
                Trs {
                    translation: t,
                    rotation: r.normalize(),
                    scale: s,
                }
            }
            None => Trs {
                translation: jn.translation.map(Vec3::from).unwrap_or(Vec3::ZERO),
                rotation: jn
                    .rotation
                    .map(|q| Quat::from_array(q.0).normalize())
                    .unwrap_or(Quat::IDENTITY),
                scale: jn.scale.map(Vec3::from).unwrap_or(Vec3::ONE),
            },
        };
        if !(rest.translation.is_finite() && rest.rotation.is_finite() && rest.scale.is_finite()) {
            return Err(src.invalid(format!("node {i} transform is not finite")));
        }
        let extras = jn
            .extras
            .as_ref()
            .and_then(|raw| serde_json::from_str::<serde_json::Value>(raw.get()).ok());
        nodes.push(Node {
            name: jn.name.clone().unwrap_or_else(|| format!("node{i}")),
            parent: None,
            children: Vec::new(),
            rest,
            bone: None,
            extras,
        });
    }
    for (i, jn) in src.root.nodes.iter().enumerate() {
        for c in jn.children.iter().flatten() {
            let c = c.value();
            if c >= n {
                return Err(src.invalid(format!(
                    "node {i} has child {c}, but there are only {n} nodes"
                )));
            }
            if c == i || nodes[c].parent.is_some() {
                return Err(src.invalid(format!(
                    "node {c} has more than one parent (the hierarchy must be a forest)"
                )));
            }
            nodes[c].parent = Some(i);
            nodes[i].children.push(c);
        }
    }
    // Parents-first order from every root; a cycle leaves nodes unreached.
    let mut order = Vec::with_capacity(n);
    let mut stack: Vec<usize> = (0..n)
        .rev()
        .filter(|&i| nodes[i].parent.is_none())
        .collect();
    while let Some(i) = stack.pop() {
        order.push(i);
        stack.extend(nodes[i].children.iter().rev().copied());
    }
    if order.len() != n {
        return Err(src.invalid("the node hierarchy contains a cycle"));
    }
    let mut depth = vec![0usize; n];
    for &i in &order {
        depth[i] = nodes[i].parent.map_or(1, |p| depth[p] + 1);
        if depth[i] > MAX_NODE_DEPTH {
            return Err(src.invalid(format!(
                "node {i} ('{}') is {} levels deep; frond refuses node hierarchies deeper than {MAX_NODE_DEPTH} levels (tree skeletons are under 30; deeper chains break glTF tools)",
                nodes[i].name, depth[i]
            )));
        }
    }
    Ok((nodes, order))
}

/// Warns about scene data frond does not rely on but a file may get wrong: a `"scene"` index
/// past the scene list, a scene root that does not exist, and a scene root that is also
/// another node's child. frond reads every node of the hierarchy whatever the scenes say, so
/// none of these changes the import; the warning says what was read instead.
pub(super) fn check_scenes(src: &GltfSource, nodes: &[Node], warnings: &mut Vec<String>) {
    let scenes = &src.root.scenes;
    if let Some(s) = src.root.scene.map(|s| s.value())
        && s >= scenes.len()
    {
        warnings.push(format!(
            "\"scene\" is {s}, but the file has {} scenes; frond reads every node regardless",
            scenes.len()
        ));
    }
    for (si, scene) in scenes.iter().enumerate() {
        for r in scene.nodes.iter().map(|r| r.value()) {
            match nodes.get(r) {
                None => warnings.push(format!(
                    "scene {si} lists node {r} as a root, but there are only {} nodes; ignored",
                    nodes.len()
                )),
                Some(node) => {
                    if let Some(p) = node.parent {
                        warnings.push(format!(
                            "scene {si} lists node {r} ('{}') as a root, but it is a child of node {p} ('{}'); read as that node's child",
                            node.name, nodes[p].name
                        ));
                    }
                }
            }
        }
    }
}

//! Trees for the metric's tests: imported, and thinned into a simplified candidate.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

use frond_scene::{ImportOptions, Tree, import};

/// `path` imported with the default options.
pub fn load(path: &Path) -> Tree {
    import(path, &ImportOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `tree`'s foliage triangles grouped into cards (a leaf quad, a frond): triangles sharing a
/// vertex belong to the same card. Cards in the order of their first triangle.
pub fn foliage_cards(tree: &Tree) -> Vec<Vec<usize>> {
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let foliage = tree.foliage();
    let mut parent: Vec<usize> = (0..foliage.len()).collect();
    let mut owner: HashMap<u32, usize> = HashMap::new();
    for (i, &t) in foliage.iter().enumerate() {
        for v in tree.triangles[t].v {
            match owner.get(&v) {
                Some(&j) => {
                    let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                    parent[a.max(b)] = a.min(b);
                }
                None => {
                    owner.insert(v, i);
                }
            }
        }
    }
    let mut cards: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for (i, &t) in foliage.iter().enumerate() {
        cards.entry(root(&mut parent, i)).or_default().push(t);
    }
    cards.into_values().collect()
}

/// `tree` without every second card of its foliage (the second, fourth, …), and how many
/// cards it had: a candidate that thins the foliage as a crude LOD does.
pub fn without_every_second_card(tree: &Tree) -> (Tree, usize) {
    let cards = foliage_cards(tree);
    let dropped: HashSet<usize> = cards.iter().skip(1).step_by(2).flatten().copied().collect();
    let mut thinned = tree.clone();
    thinned.triangles = (tree.triangles.iter().enumerate())
        .filter(|(i, _)| !dropped.contains(i))
        .map(|(_, t)| *t)
        .collect();
    (thinned, cards.len())
}

//! k-means over animation descriptions (spec animated-billboard-clouds §4.11 step 1, App. C.1):
//! a description type's `deviation` is the distance and its `average` the centroid, so this is
//! written here rather than taken from linfa, whose k-means is Euclidean only. Restarts from
//! seeded k-means++ starts and from the skeleton (one cluster per bone, split or merged to k);
//! the run with the lowest weighted squared error is kept.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::description::DescriptionType;

/// A clustering of descriptions.
#[derive(Clone, Debug)]
pub struct Clustering<D> {
    /// Cluster of each description, in 0..centroids.len().
    pub assignment: Vec<usize>,
    /// The average description of each cluster.
    pub centroids: Vec<D>,
    /// Σ w · deviation(d, centroid)² over all descriptions.
    pub error: f64,
    /// Assignment rounds until nothing moved (or the cap).
    pub iterations: usize,
    /// Which start won: `"skeleton"` or `"random <i>"`.
    pub start: String,
}

fn centroids<T: DescriptionType>(
    ty: &T,
    descs: &[T::Desc],
    weights: &[f32],
    assignment: &[usize],
    k: usize,
) -> Vec<T::Desc> {
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); k];
    for (i, &c) in assignment.iter().enumerate() {
        members[c].push(i);
    }
    members
        .par_iter()
        .map(|m| {
            let ds: Vec<&T::Desc> = m.iter().map(|&i| &descs[i]).collect();
            let ws: Vec<f32> = m.iter().map(|&i| weights[i]).collect();
            ty.average(&ds, &ws)
        })
        .collect()
}

/// Nearest centroid of every description (ties to the lower index) and its deviation.
fn assign<T: DescriptionType>(ty: &T, descs: &[T::Desc], cents: &[T::Desc]) -> Vec<(usize, f32)> {
    descs
        .par_iter()
        .map(|d| {
            let mut best = (0usize, f32::INFINITY);
            for (c, cent) in cents.iter().enumerate() {
                let dev = ty.deviation(d, cent);
                if dev < best.1 {
                    best = (c, dev);
                }
            }
            best
        })
        .collect()
}

/// Lloyd's iterations from `initial` (a cluster per description, labels 0..k). A cluster left
/// empty takes the description farthest from its centroid, so k clusters survive while there
/// are at least k descriptions.
pub fn kmeans_from<T: DescriptionType>(
    ty: &T,
    descs: &[T::Desc],
    weights: &[f32],
    initial: Vec<usize>,
    max_iterations: usize,
) -> Clustering<T::Desc> {
    let k = initial.iter().copied().max().map_or(0, |m| m + 1);
    let mut assignment = initial;
    let mut cents = centroids(ty, descs, weights, &assignment, k);
    let mut iterations = 0;
    let mut nearest = assign(ty, descs, &cents);
    while iterations < max_iterations {
        iterations += 1;
        let mut next: Vec<usize> = nearest.iter().map(|&(c, _)| c).collect();
        // Refill empty clusters with the worst-fitting descriptions.
        let mut counts = vec![0usize; k];
        for &c in &next {
            counts[c] += 1;
        }
        let mut order: Vec<usize> = (0..descs.len()).collect();
        order.sort_by(|&a, &b| nearest[b].1.total_cmp(&nearest[a].1).then(a.cmp(&b)));
        let mut donors = order.into_iter();
        for c in 0..k {
            if counts[c] == 0 {
                for d in donors.by_ref() {
                    if counts[next[d]] > 1 {
                        counts[next[d]] -= 1;
                        next[d] = c;
                        counts[c] = 1;
                        break;
                    }
                }
            }
        }
        if next == assignment {
            break;
        }
        assignment = next;
        cents = centroids(ty, descs, weights, &assignment, k);
        nearest = assign(ty, descs, &cents);
    }
    let error = descs
        .iter()
        .zip(&assignment)
        .zip(weights)
        .map(|((d, &c), &w)| {
            let dev = f64::from(ty.deviation(d, &cents[c]));
            f64::from(w) * dev * dev
        })
        .sum();
    Clustering {
        assignment,
        centroids: cents,
        error,
        iterations,
        start: String::new(),
    }
}

/// A seeded k-means++ start: the first seed uniform, each next one drawn with probability
/// proportional to the squared deviation from the nearest seed so far; every description then
/// joins its nearest seed.
pub fn kmeans_plus_plus<T: DescriptionType>(
    ty: &T,
    descs: &[T::Desc],
    k: usize,
    seed: u64,
) -> Vec<usize> {
    let n = descs.len();
    if n == 0 || k == 0 {
        return vec![0; n];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut seeds = vec![rng.random_range(0..n)];
    let mut best: Vec<f32> = descs
        .par_iter()
        .map(|d| ty.deviation(d, &descs[seeds[0]]))
        .collect();
    while seeds.len() < k.min(n) {
        let total: f64 = best.iter().map(|&x| f64::from(x) * f64::from(x)).sum();
        let pick = if total > 0.0 {
            let mut r = rng.random_range(0.0..total);
            let mut chosen = n - 1;
            for (i, &b) in best.iter().enumerate() {
                r -= f64::from(b) * f64::from(b);
                if r <= 0.0 {
                    chosen = i;
                    break;
                }
            }
            chosen
        } else {
            // Every description equals a seed: any unused one.
            (0..n).find(|i| !seeds.contains(i)).unwrap_or(0)
        };
        seeds.push(pick);
        let s = &descs[pick];
        best.par_iter_mut()
            .zip(descs.par_iter())
            .for_each(|(b, d)| *b = b.min(ty.deviation(d, s)));
    }
    let cents: Vec<T::Desc> = seeds.iter().map(|&i| descs[i].clone()).collect();
    assign(ty, descs, &cents)
        .into_iter()
        .map(|(c, _)| c)
        .collect()
}

/// The skeleton start of App. C.1: one cluster per bone (`bone[i]` of each description); while
/// there are more than `k`, merge the two whose averages deviate least (agglomerative, one
/// deviation row recomputed per merge); while fewer, split the cluster of the highest variance
/// (mean squared deviation from its average) at its members' mean distance from their bone's
/// start joint (`start_distance[i]`). Clusters that cannot split (one member, or all at one
/// distance) are skipped.
pub fn skeleton_start<T: DescriptionType>(
    ty: &T,
    descs: &[T::Desc],
    weights: &[f32],
    bone: &[usize],
    start_distance: &[f32],
    k: usize,
) -> Vec<usize> {
    let n = descs.len();
    let k = k.clamp(1, n.max(1));
    // Clusters as member lists, in bone order.
    let mut bones: Vec<usize> = bone.to_vec();
    bones.sort_unstable();
    bones.dedup();
    let mut clusters: Vec<Vec<usize>> = bones
        .iter()
        .map(|b| (0..n).filter(|&i| bone[i] == *b).collect())
        .collect();
    clusters.retain(|c| !c.is_empty());
    let average = |m: &[usize]| {
        let ds: Vec<&T::Desc> = m.iter().map(|&i| &descs[i]).collect();
        let ws: Vec<f32> = m.iter().map(|&i| weights[i]).collect();
        ty.average(&ds, &ws)
    };
    if clusters.len() > k {
        let mut avgs: Vec<T::Desc> = clusters.par_iter().map(|m| average(m)).collect();
        // Pairwise deviations of the averages, upper triangle.
        let mut dist: Vec<Vec<f32>> = (0..avgs.len())
            .into_par_iter()
            .map(|i| {
                (0..avgs.len())
                    .map(|j| {
                        if j > i {
                            ty.deviation(&avgs[i], &avgs[j])
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect()
            })
            .collect();
        let mut alive = vec![true; clusters.len()];
        let mut count = clusters.len();
        while count > k {
            let mut best = (f32::INFINITY, 0, 0);
            for i in 0..dist.len() {
                if !alive[i] {
                    continue;
                }
                for j in i + 1..dist.len() {
                    if alive[j] && dist[i][j] < best.0 {
                        best = (dist[i][j], i, j);
                    }
                }
            }
            let (_, i, j) = best;
            if i == j {
                break;
            }
            let moved = std::mem::take(&mut clusters[j]);
            clusters[i].extend(moved);
            clusters[i].sort_unstable();
            alive[j] = false;
            count -= 1;
            avgs[i] = average(&clusters[i]);
            let row: Vec<f32> = (0..avgs.len())
                .into_par_iter()
                .map(|o| {
                    if o != i && alive[o] {
                        ty.deviation(&avgs[i], &avgs[o])
                    } else {
                        f32::INFINITY
                    }
                })
                .collect();
            for (o, &d) in row.iter().enumerate() {
                if o < i {
                    dist[o][i] = d;
                } else if o > i {
                    dist[i][o] = d;
                }
            }
        }
        clusters = clusters
            .into_iter()
            .zip(alive)
            .filter(|(_, a)| *a)
            .map(|(c, _)| c)
            .collect();
    }
    let mut unsplittable = vec![false; clusters.len()];
    let variance = |m: &[usize]| -> f64 {
        let a = average(m);
        // Deviations in parallel, summed in order: the same variance whatever the threads.
        let squares: Vec<f64> = m
            .par_iter()
            .map(|&i| {
                let d = f64::from(ty.deviation(&descs[i], &a));
                d * d
            })
            .collect();
        squares.iter().sum::<f64>() / m.len().max(1) as f64
    };
    // Variances change only for the two halves of a split: kept per cluster.
    let mut variances: Vec<f64> = if clusters.len() < k {
        clusters.iter().map(|m| variance(m)).collect()
    } else {
        Vec::new()
    };
    while clusters.len() < k {
        let pick = (0..clusters.len())
            .filter(|&c| !unsplittable[c])
            .map(|c| (variances[c], c))
            .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
        let Some((_, c)) = pick else { break };
        let m = &clusters[c];
        let mean = m.iter().map(|&i| f64::from(start_distance[i])).sum::<f64>() / m.len() as f64;
        let (far, near): (Vec<usize>, Vec<usize>) = m
            .iter()
            .partition(|&&i| f64::from(start_distance[i]) > mean);
        if far.is_empty() || near.is_empty() {
            unsplittable[c] = true;
            continue;
        }
        variances[c] = variance(&near);
        variances.push(variance(&far));
        clusters[c] = near;
        clusters.push(far);
        unsplittable.push(false);
    }
    let mut assignment = vec![0usize; n];
    for (c, m) in clusters.iter().enumerate() {
        for &i in m {
            assignment[i] = c;
        }
    }
    assignment
}

/// k-means with restarts (App. C.1): the skeleton start (when `bone` is given) and `restarts`
/// seeded k-means++ starts; the lowest error wins, ties to the earlier start. `k` is capped at
/// the number of descriptions.
#[expect(
    clippy::too_many_arguments,
    reason = "k-means over descriptions: type, data, weights, k, start, restarts, seed and bins"
)]
pub fn cluster_descriptions<T: DescriptionType>(
    ty: &T,
    descs: &[T::Desc],
    weights: &[f32],
    k: usize,
    skeleton: Option<(&[usize], &[f32])>,
    restarts: usize,
    seed: u64,
    max_iterations: usize,
) -> Clustering<T::Desc> {
    let k = k.clamp(1, descs.len().max(1));
    let mut starts: Vec<(String, Vec<usize>)> = Vec::new();
    if let Some((bone, dist)) = skeleton {
        starts.push((
            "skeleton".into(),
            skeleton_start(ty, descs, weights, bone, dist, k),
        ));
    }
    for r in 0..restarts {
        starts.push((
            format!("random {r}"),
            kmeans_plus_plus(ty, descs, k, seed.wrapping_add(r as u64)),
        ));
    }
    if starts.is_empty() {
        starts.push(("random 0".into(), kmeans_plus_plus(ty, descs, k, seed)));
    }
    let mut best: Option<Clustering<T::Desc>> = None;
    for (name, init) in starts {
        let mut c = kmeans_from(ty, descs, weights, compact(init), max_iterations);
        c.start = name;
        if best.as_ref().is_none_or(|b| c.error < b.error) {
            best = Some(c);
        }
    }
    best.unwrap_or_else(|| Clustering {
        assignment: Vec::new(),
        centroids: Vec::new(),
        error: 0.0,
        iterations: 0,
        start: String::new(),
    })
}

/// Relabels clusters 0..m in order of first appearance, dropping unused labels.
fn compact(assignment: Vec<usize>) -> Vec<usize> {
    let mut map = std::collections::HashMap::new();
    assignment
        .into_iter()
        .map(|c| {
            let next = map.len();
            *map.entry(c).or_insert(next)
        })
        .collect()
}

//! Which trees a shard of a batch takes: a fixed hash of each input's path relative to INPUT,
//! so every process of a Kubernetes Indexed Job or Slurm array picks a disjoint subset
//! without talking to the others.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard this is, below `count`.
    pub index: u64,
    /// How many shards the batch is split into (at least 1).
    pub count: u64,
}

impl Shard {
    /// Parses `i/n` (0 ≤ i < n).
    pub fn parse(text: &str) -> Result<Shard> {
        let (i, n) = text
            .split_once('/')
            .with_context(|| format!("shard '{text}': expected i/n, like 0/4, or auto"))?;
        let index: u64 = i
            .trim()
            .parse()
            .with_context(|| format!("shard '{text}': '{i}' is not a shard index"))?;
        let count: u64 = n
            .trim()
            .parse()
            .with_context(|| format!("shard '{text}': '{n}' is not a shard count"))?;
        Shard::new(index, count).with_context(|| format!("shard '{text}'"))
    }

    fn new(index: u64, count: u64) -> Result<Shard> {
        if count == 0 {
            bail!("the shard count must be at least 1");
        }
        if index >= count {
            bail!("shard index {index} is not below the count {count} (indices start at 0)");
        }
        Ok(Shard { index, count })
    }

    /// The shard of this process from the job array engine's variables: Kubernetes Indexed
    /// Jobs (`JOB_COMPLETION_INDEX` of `JOB_COMPLETIONS`) or Slurm arrays
    /// (`SLURM_ARRAY_TASK_ID` − `SLURM_ARRAY_TASK_MIN` of `SLURM_ARRAY_TASK_COUNT`).
    pub fn from_env(var: &dyn Fn(&str) -> Option<String>) -> Result<Shard> {
        let num = |name: &str| -> Result<Option<u64>> {
            match var(name) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse()
                    .map(Some)
                    .with_context(|| format!("shard auto: {name}='{v}' is not a number")),
            }
        };
        if let Some(index) = num("JOB_COMPLETION_INDEX")? {
            let count = num("JOB_COMPLETIONS")?.context(
                "shard auto: JOB_COMPLETION_INDEX is set but JOB_COMPLETIONS is not (add it \
                 to the Job's env from spec.completions)",
            )?;
            return Shard::new(index, count).context("shard auto (Kubernetes)");
        }
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let count = num("SLURM_ARRAY_TASK_COUNT")?.context(
                "shard auto: SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not",
            )?;
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let index = id.checked_sub(min).with_context(|| {
                format!("shard auto: SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}")
            })?;
            return Shard::new(index, count).context(
                "shard auto (Slurm; use a contiguous --array range such as 0-7 so that ID − MIN \
                 runs over 0..COUNT)",
            );
        }
        bail!(
            "shard auto: neither JOB_COMPLETION_INDEX (Kubernetes Indexed Job) nor \
             SLURM_ARRAY_TASK_ID (Slurm array) is set"
        )
    }

    /// Whether the tree at `relative` (INPUT-relative, `/`-separated) belongs to this shard.
    pub fn takes(&self, relative: &str) -> bool {
        shard_of(relative, self.count) == self.index
    }

    /// File-name tag of this shard's summary (`shard-0002-of-0008`).
    pub fn tag(&self) -> String {
        format!("shard-{:04}-of-{:04}", self.index, self.count)
    }
}

/// The shard (of `count`) a relative path falls in: the first 8 bytes of its SHA-256, mod count.
pub fn shard_of(relative: &str, count: u64) -> u64 {
    let digest = Sha256::digest(relative.as_bytes());
    let mut first = [0u8; 8];
    first.copy_from_slice(&digest[..8]);
    u64::from_be_bytes(first) % count.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(pairs: &'static [(&'static str, &'static str)]) -> impl Fn(&str) -> Option<String> {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn parse_and_env() {
        assert_eq!(Shard::parse("1/4").unwrap(), Shard { index: 1, count: 4 });
        assert!(Shard::parse("4/4").is_err());
        assert!(Shard::parse("0/0").is_err());
        assert!(Shard::parse("x").is_err());
        let k8s = env(&[("JOB_COMPLETION_INDEX", "2"), ("JOB_COMPLETIONS", "3")]);
        assert_eq!(Shard::from_env(&k8s).unwrap(), Shard { index: 2, count: 3 });
        let slurm = env(&[
            ("SLURM_ARRAY_TASK_ID", "5"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ]);
        assert_eq!(
            Shard::from_env(&slurm).unwrap(),
            Shard { index: 4, count: 8 }
        );
        assert!(Shard::from_env(&env(&[])).is_err());
        assert!(Shard::from_env(&env(&[("JOB_COMPLETION_INDEX", "1")])).is_err());
    }

    #[test]
    fn every_path_in_exactly_one_shard_and_spread() {
        let paths: Vec<String> = (0..400).map(|i| format!("trees/t{i}.glb")).collect();
        for n in [1u64, 2, 3, 7] {
            let mut per = vec![0usize; n as usize];
            for p in &paths {
                let takers: Vec<u64> = (0..n)
                    .filter(|&i| Shard { index: i, count: n }.takes(p))
                    .collect();
                assert_eq!(takers.len(), 1, "{p} in {takers:?}");
                per[takers[0] as usize] += 1;
            }
            // A fair hash: no shard gets under half its share of 400 paths.
            assert!(per.iter().all(|&c| c * 2 * n as usize >= 400), "{per:?}");
        }
    }
}

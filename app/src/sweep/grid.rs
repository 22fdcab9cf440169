//! The parameter grid of `frond sweep`: LOD screen heights (the screen-space rule sizes ε,
//! textures and the colour metric's images), or fixed plane tolerances that override the rule.

use anyhow::{Context, Result, bail};
use frond_scene::Length;

/// What varies across the runs of one method and seed.
#[derive(Clone, Debug, PartialEq)]
pub enum Grid {
    /// One LOD per screen height (pixels); ε = pixel budget × tree height / height.
    ScreenHeights(Vec<f32>),
    /// Fixed ε values (world units), each built and evaluated at `screen_height` (texture
    /// density and image size).
    Epsilons {
        /// The ε values, world units, in the order given.
        values: Vec<f32>,
        /// Screen height in pixels every ε is built and evaluated at.
        screen_height: f32,
    },
}

/// One point of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPoint {
    /// Screen height the LOD is built and evaluated at.
    pub screen_height: f32,
    /// The fixed ε, or None when the screen-space rule derives it.
    pub epsilon: Option<f32>,
}

impl Grid {
    /// Every point, in order.
    pub fn points(&self) -> Vec<GridPoint> {
        match self {
            Grid::ScreenHeights(h) => h
                .iter()
                .map(|&screen_height| GridPoint {
                    screen_height,
                    epsilon: None,
                })
                .collect(),
            Grid::Epsilons {
                values,
                screen_height,
            } => values
                .iter()
                .map(|&e| GridPoint {
                    screen_height: *screen_height,
                    epsilon: Some(e),
                })
                .collect(),
        }
    }
}

/// Parses `--epsilon`: a range `A..B` sampled at `steps` evenly spaced values (both ends
/// included), or a comma list `A,B,C`. Each value is a length or a percentage of `diagonal`
/// ("2%"), as in `frond cloud`/`frond lod`.
pub fn parse_epsilons(text: &str, steps: usize, diagonal: f32) -> Result<Vec<f32>> {
    let one = |s: &str| -> Result<f32> {
        let v = s
            .trim()
            .parse::<Length>()
            .map(|l| l.resolve(diagonal))
            .with_context(|| format!("ε '{s}': expected a length or a percentage"))?;
        if !(v.is_finite() && v >= 0.0) {
            bail!("ε '{s}': must be a non-negative length");
        }
        Ok(v)
    };
    if let Some((a, b)) = text.split_once("..") {
        let (a, b) = (one(a)?, one(b)?);
        if steps == 0 {
            bail!("the number of ε steps must be at least 1");
        }
        if b < a {
            bail!("the ε range {text}: the range must go from the smaller to the larger value");
        }
        if steps == 1 {
            return Ok(vec![a]);
        }
        Ok((0..steps)
            .map(|i| a + (b - a) * i as f32 / (steps - 1) as f32)
            .collect())
    } else {
        text.split(',').map(one).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_include_both_ends() {
        let v = parse_epsilons("1%..6%", 6, 100.0).unwrap();
        assert_eq!(v.len(), 6);
        for (i, e) in v.iter().enumerate() {
            assert!((e - (1.0 + i as f32)).abs() < 1e-5, "{v:?}");
        }
        assert_eq!(parse_epsilons("0.5..2", 1, 10.0).unwrap(), vec![0.5]);
        let list = parse_epsilons("0.5,2%", 3, 10.0).unwrap();
        assert_eq!(list.len(), 2);
        assert_eq!(list[0], 0.5);
        assert!((list[1] - 0.2).abs() < 1e-6);
    }

    #[test]
    fn bad_ranges_are_refused() {
        assert!(parse_epsilons("5%..1%", 3, 10.0).is_err());
        assert!(parse_epsilons("1..2", 0, 10.0).is_err());
        assert!(parse_epsilons("a..2", 3, 10.0).is_err());
        assert!(parse_epsilons("-1", 3, 10.0).is_err());
    }

    #[test]
    fn grid_points() {
        let g = Grid::Epsilons {
            values: vec![0.1, 0.2],
            screen_height: 600.0,
        };
        let p = g.points();
        assert_eq!(p.len(), 2);
        assert_eq!(p[1].epsilon, Some(0.2));
        assert_eq!(p[1].screen_height, 600.0);
        let h = Grid::ScreenHeights(vec![600.0, 60.0]).points();
        assert_eq!(h[1].screen_height, 60.0);
        assert_eq!(h[1].epsilon, None);
    }
}

//! A length the user gives on the command line or in a manifest: world units (`0.5`) or a
//! percentage of the tree's rest-pose bounding-box diagonal (`2%`). Parsed once, at the edge;
//! the pipeline resolves it against the tree it works on.

use std::fmt;
use std::str::FromStr;

/// A non-negative length in world units or as a fraction of the bounding-box diagonal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    /// World units.
    World(f32),
    /// Percent of the diagonal, as written (`2` for `2%`).
    Percent(f32),
}

/// Why a text is not a [`Length`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{0}': expected a non-negative length or a percentage like 2%")]
pub struct LengthError(pub String);

impl Length {
    /// The length in world units for a tree of rest diagonal `diagonal`. Zero becomes
    /// `1e-5 · diagonal`: a tolerance of exactly zero would split coplanar triangles over
    /// float noise.
    pub fn resolve(self, diagonal: f32) -> f32 {
        let value = match self {
            Length::World(v) => v,
            Length::Percent(p) => p / 100.0 * diagonal,
        };
        if value == 0.0 { 1e-5 * diagonal } else { value }
    }
}

impl FromStr for Length {
    type Err = LengthError;
    fn from_str(text: &str) -> Result<Length, LengthError> {
        let t = text.trim();
        let err = || LengthError(text.to_string());
        let length = match t.strip_suffix('%') {
            Some(p) => Length::Percent(p.trim().parse::<f32>().map_err(|_| err())?),
            None => Length::World(t.parse::<f32>().map_err(|_| err())?),
        };
        let v = match length {
            Length::World(v) | Length::Percent(v) => v,
        };
        if !v.is_finite() || v < 0.0 {
            return Err(err());
        }
        Ok(length)
    }
}

impl fmt::Display for Length {
    /// Writes the length back as it parses (`0.5`, `2%`), for child command lines.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Length::World(v) => write!(f, "{v}"),
            Length::Percent(p) => write!(f, "{p}%"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_resolves() {
        let l: Length = "2%".parse().expect("percent");
        assert_eq!(l, Length::Percent(2.0));
        assert!((l.resolve(50.0) - 1.0).abs() < 1e-6);
        assert_eq!(" 0.5 ".parse::<Length>(), Ok(Length::World(0.5)));
        assert_eq!("0".parse::<Length>().map(|l| l.resolve(2.0)), Ok(2e-5));
        for bad in ["", "%", "-1", "x", "inf", "NaN%", "1.5cm"] {
            assert!(bad.parse::<Length>().is_err(), "{bad}");
        }
    }

    #[test]
    fn display_round_trips() {
        for text in ["0.5", "2%", "0.125%", "3"] {
            let l: Length = text.parse().expect("parses");
            assert_eq!(l.to_string().parse::<Length>(), Ok(l), "{text}");
        }
    }
}

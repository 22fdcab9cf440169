//! The rendered image plus its exact coverage mask.

/// One rendered image: sRGB RGBA8 pixels, top row first, and which pixels any
/// geometry covered (after the alpha test).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes, row-major, top row first, sRGB-encoded RGBA8.
    /// Covered pixels have alpha 255; uncovered ones hold the background colour.
    pub rgba: Vec<u8>,
    /// `width * height` flags, true where some fragment passed the alpha test (or blended
    /// layers compose to at least ½).
    pub coverage: Vec<bool>,
    /// `width * height` coverage values: 255 where something opaque or alpha-tested covers the
    /// pixel, blended layers' composed `1 − Π(1 − α)` in 0..255 elsewhere (a render without
    /// blended materials holds 0 and 255 alone).
    pub coverage_alpha: Vec<u8>,
}

impl Frame {
    /// Fraction of pixels covered by geometry, 0.0 for an empty image.
    pub fn coverage_fraction(&self) -> f64 {
        if self.coverage.is_empty() {
            return 0.0;
        }
        self.covered_count() as f64 / self.coverage.len() as f64
    }

    /// Number of covered pixels.
    pub fn covered_count(&self) -> usize {
        self.coverage.iter().filter(|&&c| c).count()
    }

    /// RGBA of pixel (x, y), y = 0 being the top row.
    ///
    /// # Panics
    /// When (x, y) is outside the image, like slice indexing; see [`Frame::get_pixel`].
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        match self.get_pixel(x, y) {
            Some(p) => p,
            None => panic!(
                "pixel ({x}, {y}) outside {}x{} frame",
                self.width, self.height
            ),
        }
    }

    /// RGBA of pixel (x, y), or `None` outside the image.
    pub fn get_pixel(&self, x: u32, y: u32) -> Option<[u8; 4]> {
        let i = self.index(x, y)? * 4;
        let p = self.rgba.get(i..i + 4)?;
        Some([p[0], p[1], p[2], p[3]])
    }

    /// Whether pixel (x, y) is covered; false outside the image.
    pub fn covered(&self, x: u32, y: u32) -> bool {
        self.index(x, y)
            .and_then(|i| self.coverage.get(i).copied())
            .unwrap_or(false)
    }

    fn index(&self, x: u32, y: u32) -> Option<usize> {
        (x < self.width && y < self.height).then(|| y as usize * self.width as usize + x as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accessors() {
        let frame = Frame {
            width: 2,
            height: 1,
            rgba: vec![1, 2, 3, 4, 5, 6, 7, 8],
            coverage: vec![false, true],
            coverage_alpha: vec![0, 255],
        };
        assert_eq!(frame.pixel(1, 0), [5, 6, 7, 8]);
        assert_eq!(frame.get_pixel(2, 0), None);
        assert!(frame.covered(1, 0) && !frame.covered(0, 0) && !frame.covered(0, 5));
        assert_eq!(frame.coverage_fraction(), 0.5);
        assert_eq!(Frame::default().coverage_fraction(), 0.0);
    }
}

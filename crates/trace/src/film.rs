//! The film: where in a pixel its samples go, how they become one 8-bit
//! RGBA value, and the PNG file.
//!
//! **Samples.** One sample is the pixel's centre. `n > 1` samples are
//! stratified: the pixel is cut into an `s × s` grid, `s = ceil(√n)`, and
//! sample `k` lies in cell `⌊k·s²/n⌋` (cells numbered row by row, every
//! other row right to left, so that the cells of a partial grid spread over
//! the pixel), jittered within it by a hash of the pixel (in full-image
//! coordinates) and `k`. Renders are therefore reproducible, and a region
//! renders exactly the pixels of the same crop of the whole image. The
//! pixel's colour is the mean of its samples' colours (a box filter), each
//! channel alone, alpha included, as GL resolves a multisampled
//! framebuffer.
//!
//! **Encoding.** `linear` writes round(255·c), as GL writes an 8-bit
//! framebuffer; `srgb` applies the sRGB transfer curve (IEC 61966-2-1) to
//! red, green and blue first. Alpha is always linear.

use glam::DVec4;
use image::ImageEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};

use crate::scene::Encoding;

/// Where the samples of a pixel go.
#[derive(Clone, Debug)]
pub struct SamplePattern {
    samples: u32,
    /// Cells per side of the grid.
    side: u32,
    /// Per sample, its grid cell `(column, row)`.
    cells: Vec<(u32, u32)>,
}

impl SamplePattern {
    pub fn new(samples: u32) -> Self {
        let samples = samples.max(1);
        let side = (f64::from(samples).sqrt().ceil() as u32).max(1);
        let cells = (0..samples)
            .map(|k| {
                let index = u64::from(k) * u64::from(side * side) / u64::from(samples);
                let row = (index / u64::from(side)) as u32;
                let column = (index % u64::from(side)) as u32;
                let column = if row % 2 == 1 {
                    side - 1 - column
                } else {
                    column
                };
                (column, row)
            })
            .collect();
        Self {
            samples,
            side,
            cells,
        }
    }

    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The offset within pixel `(x, y)` of sample `k`, each coordinate in
    /// [0, 1): the centre for a single sample.
    #[inline]
    pub fn offset(&self, x: u32, y: u32, k: u32) -> (f64, f64) {
        if self.samples == 1 {
            return (0.5, 0.5);
        }
        let (column, row) = self.cells[k as usize];
        let h = mix(mix((u64::from(x) << 32) | u64::from(y)) ^ u64::from(k));
        // Two 24-bit uniforms in [0, 1).
        let jx = (h >> 40) as f64 / (1u64 << 24) as f64;
        let jy = ((h >> 8) & 0xff_ffff) as f64 / (1u64 << 24) as f64;
        let side = f64::from(self.side);
        (
            (f64::from(column) + jx) / side,
            (f64::from(row) + jy) / side,
        )
    }
}

/// SplitMix64's finaliser (Steele et al., *Fast Splittable Pseudorandom
/// Number Generators*, 2014): a bijective mix of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// One colour in [0, 1] as an 8-bit RGBA value.
#[inline]
pub fn encode(c: DVec4, encoding: Encoding) -> [u8; 4] {
    let c = c.clamp(DVec4::ZERO, DVec4::ONE);
    let c = match encoding {
        Encoding::Linear => c,
        Encoding::Srgb => DVec4::new(
            srgb_transfer(c.x),
            srgb_transfer(c.y),
            srgb_transfer(c.z),
            c.w,
        ),
    };
    // round(255·x) for x in [0, 1] by adding ½ and truncating (the two
    // differ only within an ulp of a tie): `round` is a library call on the
    // baseline x86-64 target.
    (255.0 * c + 0.5).as_u8vec4().to_array()
}

/// The sRGB transfer curve (IEC 61966-2-1) from linear [0, 1].
pub fn srgb_transfer(c: f64) -> f64 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Encodes RGBA8 pixels (row by row from the top) as a PNG.
///
/// With `CompressionType::Fast`: at 1920×1080 it is about ten times faster
/// than the default level, for files a little larger; a rendered image is
/// sent once, so the time matters more than the bytes. For the same reason
/// every row takes the `Sub` filter (each byte minus the same channel of
/// the pixel to its left): on the 100k-triangle benchmark frame, 7.3 ms and
/// 478 KB, against 11.3 ms and 454 KB for the adaptive choice per row, which
/// tries all five filters.
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rgba.len() / 4 + 1024);
    PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Sub)
        .write_image(rgba, width, height, image::ExtendedColorType::Rgba8)
        .expect("encoding RGBA8 pixels into memory cannot fail");
    out
}

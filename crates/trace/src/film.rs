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
//! **Adaptive sampling** spends samples where the image needs them, each
//! pixel's samples a function of its own coordinates alone (so a region
//! still renders exactly the pixels of the whole image). A pixel first
//! takes its four corners (shared with its neighbours, so they cost about
//! one sample per pixel) and its centre: [`FIRST`] samples. Two estimates
//! of its mean colour follow, the corners' mean `m` and the rule
//! `(m + 2·centre)/3`, which is exact for any colour quadratic across the
//! pixel (the product rule of the corners and the centre; Simpson's rule in
//! each direction). Where the two differ by at most the tolerance on every
//! channel the pixel is settled: its colour is the second, and their
//! difference, an upper estimate of its error, is the pixel's estimated
//! error. Smooth shading settles there, whatever its gradient; an edge, a
//! shadow or a highlight's rim through the pixel does not. Such a pixel
//! drops those samples and takes sets of [`SET`] stratified samples inside
//! it (each set a 4×4 grid jittered by its own hash) until the standard
//! error of their mean is within the tolerance, or the most samples
//! allowed are taken (a last set may be smaller). That standard error is
//! the one of a stratified mean ([`SetMoments`]): it counts only the
//! variance within the grid's cells, estimated from the contrasts of each
//! set's grid that smooth colour and straight edges barely excite, and
//! from the spread between sets; the iid estimate `√(s²/n)` would also
//! count the differences between cells, which stratification removes, and
//! overstates an edge pixel's error several times. It is the pixel's
//! estimated error. This is the scheme of adaptive samplers such as
//! pbrt-v2's (`src/samplers/adaptive.cpp`): refine a pixel where its first
//! samples disagree.
//!
//! **Encoding.** `linear` writes round(255·c), as GL writes an 8-bit
//! framebuffer; `srgb` applies the sRGB transfer curve (IEC 61966-2-1) to
//! red, green and blue first. Alpha is always linear.

use glam::{DVec4, Vec4};
use image::ImageEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};

use crate::scene::Encoding;

/// The samples of one set of adaptive sampling: a 4×4 grid.
pub const SET: u32 = 16;

/// The first samples of adaptive sampling, as a pixel counts them: its
/// four corners and its centre.
pub const FIRST: u32 = 5;

/// A pixel of adaptive sampling from its first samples, its `corners` and
/// its `centre`: its colour and estimated error when the two estimates
/// agree within `tolerance` on every channel, else `None` (see the module
/// docs).
pub fn settled(corners: &[DVec4; 4], centre: DVec4, tolerance: f64) -> Option<(DVec4, f64)> {
    let mean = Moments::of(corners).mean();
    // `mean − (mean + 2·centre)/3`, exactly 0 where the samples agree.
    let error = (2.0 / 3.0) * (mean - centre).abs().max_element();
    (error <= tolerance).then(|| ((mean + 2.0 * centre) / 3.0, error))
}

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

    /// Sample `k`'s cell of the grid, `(column, row)`.
    pub fn cell(&self, k: u32) -> (u32, u32) {
        self.cells[k as usize]
    }

    /// The offset within pixel `(x, y)` of sample `k`, each coordinate in
    /// [0, 1): the centre for a single sample.
    #[inline]
    pub fn offset(&self, x: u32, y: u32, k: u32) -> (f64, f64) {
        self.jittered(x, y, k, u64::from(k))
    }

    /// The offset within pixel `(x, y)` of sample `k` of adaptive set
    /// `set`: the same cells, jittered by another hash for every set.
    #[inline]
    pub fn offset_in_set(&self, x: u32, y: u32, set: u32, k: u32) -> (f64, f64) {
        self.jittered(x, y, k, u64::from(k) | (u64::from(set) + 1) << 32)
    }

    /// Sample `k`'s cell, jittered by the hash of the pixel and `key`.
    #[inline]
    fn jittered(&self, x: u32, y: u32, k: u32, key: u64) -> (f64, f64) {
        if self.samples == 1 {
            return (0.5, 0.5);
        }
        let (column, row) = self.cells[k as usize];
        let h = mix(mix((u64::from(x) << 32) | u64::from(y)) ^ key);
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

/// The running sums of a pixel's sample colours: their mean and the
/// estimated standard error of that mean.
#[derive(Clone, Copy, Debug, Default)]
pub struct Moments {
    pub count: u32,
    sum: DVec4,
    squares: DVec4,
}

impl Moments {
    /// The moments of `colors`, in order.
    pub fn of(colors: &[DVec4]) -> Self {
        let mut moments = Self::default();
        colors.iter().for_each(|&c| moments.add(c));
        moments
    }

    #[inline]
    pub fn add(&mut self, color: DVec4) {
        self.count += 1;
        self.sum += color;
        self.squares += color * color;
    }

    /// The samples' mean: their sum (in the order added) over their count.
    #[inline]
    pub fn mean(&self) -> DVec4 {
        self.sum / f64::from(self.count)
    }

    /// On the channel where it is largest, `√(s²/n)`, `s²` the samples'
    /// unbiased variance (`(Σc² − Σc·mean)/(n − 1)`, exact enough for
    /// colours of a few units); 0 for one sample.
    pub fn standard_error(&self) -> f64 {
        if self.count < 2 {
            return 0.0;
        }
        let n = f64::from(self.count);
        let variance = ((self.squares - self.sum * self.mean()) / (n - 1.0)).max(DVec4::ZERO);
        (variance / n).max_element().sqrt()
    }
}

/// The Walsh functions on the four rows (or columns) of a set's grid, in
/// sequency order: the mean, then one, two and three changes of sign.
const WALSH: [[f64; 4]; 4] = [
    [1.0, 1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0, -1.0],
];

/// The contrasts of a set's 4×4 grid that measure its noise: the products
/// of a column's and a row's Walsh function, `(column sequency, row
/// sequency)`, both with two or three changes of sign (see [`SetMoments`]).
const CONTRASTS: [(usize, usize); 4] = [(2, 2), (2, 3), (3, 2), (3, 3)];

/// The running sums of a pixel's sets of stratified samples (see the module
/// docs): their mean and an estimate of its standard error that counts
/// only what stratification leaves.
///
/// Stratified samples, one jittered in each cell of a grid, have a mean
/// whose variance is `Σσ²_h / n²`, `σ²_h` the variance of a sample within
/// cell `h`: the differences between the cells' means, which the iid
/// estimate `s²/n` counts, are no error of a stratified mean. For an edge
/// through the pixel only the cells it crosses have `σ²_h > 0`, so `s²/n`
/// overstates the error several times. With one sample per cell, `Σσ²_h`
/// is estimated by contrasts, as for collapsed strata (Cochran, *Sampling
/// Techniques*, 3rd ed., §5A.12): for weights `w_h = ±1`, independent
/// samples give `E[(Σ w_h c_h)²] = Σσ²_h + (Σ w_h μ_h)²`, the variance
/// sought plus the contrast of the cells' means, so each contrast is an
/// estimate that errs only upwards. The contrasts used are the grid's
/// interactions of highest sequency, products of a column's and a row's
/// Walsh function with two or three changes of sign each: they are blind
/// to any colour that is a function of the column plus one of the row (a
/// ramp, an edge along the grid), and an edge at any angle, which gives
/// the cells' means a smooth pattern of coverage, excites them little,
/// unlike the interactions with one change of sign (the pixel's halves
/// against each other). Between full sets, independent replicates of the
/// same pattern, the spread of their sums estimates the same `Σσ²_h`
/// without that bias (`Σ_j (S_j − S̄)²` has expectation `(k − 1)·Σσ²_h`).
/// The estimate pools the two, every term weighted alike: four terms for
/// the first set, five for each further one.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetMoments {
    all: Moments,
    /// The full sets: how many, the sum of their contrasts' squares, and
    /// of their sums and those sums' squares.
    sets: u32,
    contrast_squares: DVec4,
    set_sums: DVec4,
    set_sum_squares: DVec4,
}

impl SetMoments {
    /// Adds one set's `colors`, sample `k` at `pattern`'s cell `k`: a full
    /// set (its [`SET`] samples on the 4×4 grid) or a last, smaller one,
    /// which counts only in the mean.
    pub fn add_set(&mut self, pattern: &SamplePattern, colors: &[DVec4]) {
        colors.iter().for_each(|&c| self.all.add(c));
        if colors.len() != SET as usize {
            return;
        }
        debug_assert_eq!(pattern.samples(), SET);
        let mut contrasts = [DVec4::ZERO; CONTRASTS.len()];
        let mut sum = DVec4::ZERO;
        for (k, &color) in colors.iter().enumerate() {
            let (column, row) = pattern.cell(k as u32);
            for (contrast, &(u, v)) in contrasts.iter_mut().zip(&CONTRASTS) {
                *contrast += WALSH[u][column as usize] * WALSH[v][row as usize] * color;
            }
            sum += color;
        }
        self.contrast_squares += contrasts.iter().map(|&c| c * c).sum::<DVec4>();
        self.sets += 1;
        self.set_sums += sum;
        self.set_sum_squares += sum * sum;
    }

    pub fn count(&self) -> u32 {
        self.all.count
    }

    pub fn mean(&self) -> DVec4 {
        self.all.mean()
    }

    /// On the channel where it is largest, the estimated standard error of
    /// the mean: `√(V/(SET·n))`, `V` the pooled estimate of `Σσ²_h` over a
    /// set's cells and `n` the samples (a last, smaller set's samples
    /// counted as if they were a full set's, although its larger cells
    /// leave each more variance); as for iid samples
    /// ([`Moments::standard_error`]) before a full set.
    pub fn standard_error(&self) -> f64 {
        if self.sets == 0 {
            return self.all.standard_error();
        }
        let sets = f64::from(self.sets);
        let between =
            (self.set_sum_squares - self.set_sums * self.set_sums / sets).max(DVec4::ZERO);
        let terms = CONTRASTS.len() as f64 * sets + sets - 1.0;
        let cells = (self.contrast_squares + between) / terms;
        (cells / (f64::from(SET) * f64::from(self.all.count)))
            .max_element()
            .sqrt()
    }
}

/// SplitMix64's finaliser (Steele et al., *Fast Splittable Pseudorandom
/// Number Generators*, 2014): a bijective mix of 64 bits.
pub(crate) fn mix(mut z: u64) -> u64 {
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

/// [`encode`] of each of `colors` (f32, converted exactly) as its
/// little-endian RGBA word, into `words` (emptied first): the same bytes,
/// computed [`ENCODED_TOGETHER`] colours at a time in vector lanes where the
/// encoding is linear (in AVX-512 instructions where the CPU has them), one
/// colour at a time for sRGB.
pub fn encode_words(colors: &[Vec4], encoding: Encoding, words: &mut Vec<u32>) {
    words.clear();
    words.resize(colors.len(), 0);
    (encode_words_fn())(colors, encoding, words)
}

type EncodeWordsFn = fn(&[Vec4], Encoding, &mut [u32]);

fn encode_words_fn() -> EncodeWordsFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") {
            return |c, e, w| {
                // SAFETY: the CPU has AVX-512F, checked just above.
                unsafe { encode_words_avx512(c, e, w) }
            };
        }
    }
    encode_words_lanes
}

/// Linear colours [`ENCODED_TOGETHER`] at a time, channel by channel:
/// [`encode`]'s clamp (`DVec4::clamp` is `max`, then `min`) and rounding,
/// truncated without the checks of a saturating conversion (for NaN and
/// the range, which the clamp rules out), so one vector instruction.
#[inline(always)]
fn encode_words_lanes(colors: &[Vec4], encoding: Encoding, words: &mut [u32]) {
    const N: usize = ENCODED_TOGETHER;
    let in_lanes = match encoding {
        Encoding::Linear => colors.len() - colors.len() % N,
        Encoding::Srgb => 0,
    };
    let groups = colors[..in_lanes].chunks_exact(N);
    for (group, out) in groups.zip(words.chunks_exact_mut(N)) {
        let channels: [f64; 4 * N] = std::array::from_fn(|i| f64::from(group[i / 4][i % 4]));
        let bytes: [u8; 4 * N] = std::array::from_fn(|i| {
            // (`f64::clamp` would keep a NaN, which `DVec4::clamp` makes 0.)
            #[allow(clippy::manual_clamp)]
            let x = 255.0 * channels[i].max(0.0).min(1.0) + 0.5;
            // SAFETY: `max` returns 0 for NaN, so `x` lies in [0.5, 255.5]
            // and truncates to an `i32`.
            unsafe { x.to_int_unchecked::<i32>() as u8 }
        });
        for (word, bytes) in out.iter_mut().zip(bytes.chunks_exact(4)) {
            *word = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
        }
    }
    for (word, c) in words.iter_mut().zip(colors).skip(in_lanes) {
        *word = u32::from_le_bytes(encode(c.as_dvec4(), encoding));
    }
}

/// How many colours [`encode_words`] encodes together.
const ENCODED_TOGETHER: usize = 4;

// `encode_words_avx512` reads a group as sixteen f32 channels in a row.
const _: () = assert!(ENCODED_TOGETHER == 4 && size_of::<Vec4>() == 16);

/// [`encode_words_lanes`] in AVX-512 instructions: a group's sixteen
/// channels in two vectors of f64, converted to their sixteen bytes at once,
/// by the same operations in the same order (the compiler's loop of the
/// portable form gathered eight groups' channels from memory instead).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn encode_words_avx512(colors: &[Vec4], encoding: Encoding, words: &mut [u32]) {
    use std::arch::x86_64::*;
    const N: usize = ENCODED_TOGETHER;
    if encoding == Encoding::Srgb {
        return encode_words_lanes(colors, encoding, words);
    }
    let (zero, one) = (_mm512_setzero_pd(), _mm512_set1_pd(1.0));
    let (scale, half) = (_mm512_set1_pd(255.0), _mm512_set1_pd(0.5));
    let groups = colors.chunks_exact(N);
    let in_lanes = colors.len() - groups.remainder().len();
    for (group, out) in groups.zip(words.chunks_exact_mut(N)) {
        let channels = group.as_ptr().cast::<f32>();
        let [low, high] = [0, 2 * 4].map(|at| {
            // SAFETY: a group's colours are 4·N f32 in a row (`Vec4` is
            // its four channels), of which this reads eight from `at`.
            let x = _mm512_cvtps_pd(unsafe { _mm256_loadu_ps(channels.add(at)) });
            // The clamp: `max` gives its second operand, 0, for NaN.
            let x = _mm512_min_pd(_mm512_max_pd(x, zero), one);
            _mm512_cvttpd_epi32(_mm512_add_pd(_mm512_mul_pd(scale, x), half))
        });
        let bytes =
            _mm512_cvtepi32_epi8(_mm512_inserti64x4::<1>(_mm512_castsi256_si512(low), high));
        // SAFETY: `out` is N words, the sixteen bytes stored.
        unsafe { _mm_storeu_si128(out.as_mut_ptr().cast(), bytes) };
    }
    for (word, c) in words.iter_mut().zip(colors).skip(in_lanes) {
        *word = u32::from_le_bytes(encode(c.as_dvec4(), encoding));
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every form of [`encode_words`] the CPU runs, the portable one and
    /// the dispatched one included, takes each colour's own bytes
    /// ([`encode`]) in both encodings: out of range, NaN, infinite, and
    /// either side of the ties of round(255·c), at every length of the
    /// last group.
    #[test]
    fn colours_encoded_together_take_each_colours_bytes() {
        let mut values = vec![
            f32::NAN,
            -0.0,
            -1.0,
            0.0,
            1.0,
            1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for k in 0..255 {
            let tie = (k as f32 + 0.5) / 255.0;
            values.extend([tie, tie.next_down(), tie.next_up()]);
        }
        let n = values.len();
        let colors: Vec<Vec4> = (0..n)
            .map(|i| {
                Vec4::new(
                    values[i],
                    values[(i * 3 + 1) % n],
                    values[(i * 5 + 2) % n],
                    values[(i * 11 + 3) % n],
                )
            })
            .collect();
        let mut forms: Vec<(&str, EncodeWordsFn)> = vec![
            ("portable", encode_words_lanes),
            ("dispatched", encode_words_fn()),
        ];
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") {
            forms.push(("avx512", |c, e, w| {
                // SAFETY: the CPU has AVX-512F, checked just above.
                unsafe { encode_words_avx512(c, e, w) }
            }));
        }
        for (name, form) in forms {
            for encoding in [Encoding::Linear, Encoding::Srgb] {
                for len in (n - 2 * ENCODED_TOGETHER..=n).chain(0..=ENCODED_TOGETHER) {
                    let mut words = vec![7; len];
                    form(&colors[..len], encoding, &mut words);
                    for (k, (word, color)) in words.iter().zip(&colors).enumerate() {
                        assert_eq!(
                            word.to_le_bytes(),
                            encode(color.as_dvec4(), encoding),
                            "{name}, {encoding:?}, {len} colours, colour {k}: {color}"
                        );
                    }
                }
            }
        }
    }
}

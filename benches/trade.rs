//! The speed-for-accuracy trade, published: for each scene and precision
//! tier, vertices per second (on one core and on all), the error against
//! the f64 reference (max, mean, and the share of 8-bit channels that
//! differ) and the error budgets (`{"max_abs_error": E}`) that select the
//! tier, beside yardsticks measured in the same run: the ceiling the
//! machine's f32 FMA rate puts on each scene (from an estimate of its FLOPs
//! per vertex), the ceiling its memory bandwidth puts there (the bytes a
//! vertex reads and writes, against a copy of a buffer as large as the
//! batch's), and plain NumPy (`benches/trade_numpy.py`, when Python with
//! NumPy is installed). Writes `docs/trade.md` and the chart `docs/trade.svg`.
//!
//! `cargo bench --bench trade` (`GLINT_TRADE_VERTICES` sets the batch size,
//! 1e6 by default).

use std::process::Command;
use std::time::{Duration, Instant};

use glam::{DVec4, Vec4};
use glint::scene::ShadeScene;
use glint_lighting::kernel::{Colors, Kernel, Tier};
use glint_lighting::{LightPosition, LightSet, Precision, Side, SurfaceMaterial, reference};
use plotters::prelude::*;
use rayon::prelude::*;

mod common;

/// Each measurement times at least this many runs, and runs for at least
/// [`MEASURE`]; the median is kept.
const RUNS: usize = 7;

/// Untimed runs first, for this long (at least one). A batch lit in 2 ms
/// runs slower in its first runs (buffers paging in, the pool's threads
/// waking): the median of 7 runs of a fresh process was below that of 200
/// in three of four alternating pairs.
const WARM_UP: Duration = Duration::from_millis(500);

/// The shortest time of the timed runs of a measurement.
const MEASURE: Duration = Duration::from_secs(1);

struct Row {
    scene: &'static str,
    tier: Precision,
    one_core: f64,
    all_cores: f64,
    max_error: f64,
    mean_error: f64,
    differing_bytes: f64,
    /// Its speed over `accurate`'s (one core, all cores) measured in the
    /// same turns ([`median_ratio`]); `None` where it was measured apart,
    /// and the ratio of the medians stands.
    paired: Option<[f64; 2]>,
}

fn main() {
    let count: usize = std::env::var("GLINT_TRADE_VERTICES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let pools = [1, cores].map(|threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    });
    let flop_rate = pools[1].install(measure_flop_rate);
    let copy_rates = pools
        .each_ref()
        .map(|pool| pool.install(|| measure_copy_rate(count)));
    let numpy = numpy_rates(count);

    let mut rows = Vec::new();
    let mut ceilings = Vec::new();
    for (name, file) in common::SCENES {
        let scene = common::scene(file, count);
        // The reference's timed runs give the colours the others are held to.
        let mut reference = Vec::new();
        let reference_seconds = pools.each_ref().map(|pool| {
            median_seconds(|| {
                reference = pool.install(|| reference_colors(&scene));
            })
        });
        // The f32 inputs are prepared once, as a vertex buffer is uploaded
        // once, and the output buffer is reused: the timed loop is the
        // lighting alone (the service pays both per request).
        let kernel = Kernel::new(&scene.lights, &scene.positions);
        let products = kernel.products(&scene.material);
        let vertices = kernel.prepare(&scene.positions, &scene.normals);
        // A row from the median seconds on one core and on all.
        let mut row = |tier, seconds: [f64; 2], paired, colors: &[Vec4]| {
            let [one_core, all_cores] = seconds.map(|s| count as f64 / s);
            let (max_error, mean_error, differing_bytes) = errors(colors, &reference);
            rows.push(Row {
                scene: name,
                tier,
                one_core,
                all_cores,
                max_error,
                mean_error,
                differing_bytes,
                paired,
            });
        };
        let reference32: Vec<Vec4> = reference.iter().map(|c| c.as_vec4()).collect();
        row(Precision::Reference, reference_seconds, None, &reference32);
        // The f32 tiers take turns, run by run, so that the machine's drift
        // (its other tenants come and go) weighs on both alike and their
        // ratio is one measured side by side.
        let (mut accurate, mut fast) = (Colors::default(), Colors::default());
        let times = pools.each_ref().map(|pool| {
            interleaved_times([
                &mut || {
                    pool.install(|| {
                        kernel.light_into(Tier::Accurate, &products, &vertices, &mut accurate)
                    })
                },
                &mut || {
                    pool.install(|| kernel.light_into(Tier::Fast, &products, &vertices, &mut fast))
                },
            ])
        });
        let medians = |tier: usize| times.each_ref().map(|t| median(&t[tier]));
        let speedups = times.each_ref().map(|[a, f]| median_ratio(a, f));
        row(
            Precision::Accurate,
            medians(0),
            Some([1.0; 2]),
            &accurate.front,
        );
        row(Precision::Fast, medians(1), Some(speedups), &fast.front);
        ceilings.push(Ceiling {
            scene: name,
            flops: flops_per_vertex(&scene.lights, &scene.material),
            bytes: bytes_per_vertex(&scene.lights),
        });
    }
    let rates = Rates {
        flop: flop_rate,
        copy: copy_rates,
    };
    let table = markdown(&rows, &ceilings, &rates, &numpy, count, cores);
    println!("{table}");
    let docs = format!("{}/docs", env!("CARGO_MANIFEST_DIR"));
    std::fs::create_dir_all(&docs).unwrap();
    std::fs::write(format!("{docs}/trade.md"), &table).unwrap();
    chart(&rows, &format!("{docs}/trade.svg")).unwrap();
    println!("wrote docs/trade.md and docs/trade.svg");
}

fn reference_colors(scene: &ShadeScene) -> Vec<DVec4> {
    scene
        .positions
        .par_iter()
        .zip(&scene.normals)
        .map(|(&p, &n)| reference::color(&scene.lights, &scene.material, Side::Front, p, n))
        .collect()
}

fn median_seconds(mut f: impl FnMut()) -> f64 {
    let [times] = interleaved_times([&mut f]);
    median(&times)
}

/// The times of each of `runs` in seconds, timed in turns (run k of each
/// before run k + 1 of any) after [`WARM_UP`].
fn interleaved_times<const N: usize>(mut runs: [&mut dyn FnMut(); N]) -> [Vec<f64>; N] {
    let warming = Instant::now();
    loop {
        runs.iter_mut().for_each(|f| f());
        if warming.elapsed() >= WARM_UP {
            break;
        }
    }
    let mut times: [Vec<f64>; N] = std::array::from_fn(|_| Vec::new());
    let measuring = Instant::now();
    while times[0].len() < RUNS || measuring.elapsed() < MEASURE {
        for (f, times) in runs.iter_mut().zip(&mut times) {
            let start = Instant::now();
            f();
            times.push(start.elapsed().as_secs_f64());
        }
    }
    times
}

/// The median of `values`.
fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[sorted.len() / 2]
}

/// The median, over the turns of [`interleaved_times`], of `slower[k]` over
/// `faster[k]`: how many times faster the second run is, each turn's pair
/// measured back to back, so that the machine's slow drifts in speed
/// (other tenants coming and going), which move both alike, cancel.
fn median_ratio(slower: &[f64], faster: &[f64]) -> f64 {
    let ratios: Vec<f64> = slower.iter().zip(faster).map(|(s, f)| s / f).collect();
    median(&ratios)
}

/// Max and mean absolute error over the RGB channels, and the share of
/// channels whose 8-bit value (round(255·c)) differs from the reference's.
fn errors(colors: &[Vec4], reference: &[DVec4]) -> (f64, f64, f64) {
    let (mut max, mut sum, mut differing) = (0.0f64, 0.0, 0usize);
    for (c, r) in colors.iter().zip(reference) {
        for k in 0..3 {
            let e = (c[k] as f64 - r[k]).abs();
            max = max.max(e);
            sum += e;
            differing += usize::from((c[k] as f64 * 255.0).round() != (r[k] * 255.0).round());
        }
    }
    let channels = (3 * colors.len()) as f64;
    (max, sum / channels, differing as f64 / channels)
}

/// An estimate of the f32 operations per vertex of the accurate kernel,
/// counted from its source (a multiply-add counts 2, a reciprocal estimate
/// or its Newton step 1 each, a power: see [`power_flops`]): what the
/// machine's FMA rate divides to give a ceiling.
fn flops_per_vertex(lights: &LightSet, material: &SurfaceMaterial) -> f64 {
    let specular = material.front.specular.truncate() != glam::DVec3::ZERO;
    let local = lights.model.local_viewer;
    let mut flops = 12.0 + 10.0 + if local { 14.0 } else { 0.0 }; // load, normalise, store
    for light in lights.lights() {
        flops += 14.0; // n·VP, ambient and diffuse
        if matches!(light.position, LightPosition::Positional(_)) {
            flops += 14.0 + 7.0; // VP and its length, attenuation
            if light.spot.is_cone() {
                // the cosine from the cross product, its power
                flops += 30.0 + power_flops(light.spot.exponent);
            }
        }
        if specular {
            // the cosine, its power, the sum
            flops += 30.0 + power_flops(material.front.shininess) + 9.0;
        }
    }
    flops
}

/// The operations of the accurate kernel's `cos^s`: for a whole `s/2` up
/// to 32, its base and binary powering (a multiplication per bit and per
/// set bit of `s/2`), else the logarithm and exponential, about 40.
fn power_flops(s: f64) -> f64 {
    let half = s / 2.0;
    if s == 0.0 {
        0.0
    } else if half.fract() == 0.0 && (1.0..=32.0).contains(&half) {
        let n = half as u32;
        4.0 + f64::from(32 - n.leading_zeros() - 1 + n.count_ones() - 1)
    } else {
        40.0
    }
}

/// What a scene asks of the machine per vertex.
struct Ceiling {
    scene: &'static str,
    /// f32 operations (estimated, see [`flops_per_vertex`]).
    flops: f64,
    /// Bytes read and written (see [`bytes_per_vertex`]).
    bytes: f64,
}

/// The machine's yardsticks, measured in the same run.
struct Rates {
    /// f32 FLOP/s, all cores.
    flop: f64,
    /// Bytes read and written per second by a copy, on one core and on all.
    copy: [f64; 2],
}

/// The bytes the kernel moves per vertex: it reads the f32 normal (12) and,
/// when the lighting depends on position, the f32 position (12), and
/// writes an RGBA f32 colour (16) per lit side.
fn bytes_per_vertex(lights: &LightSet) -> f64 {
    let read = if lights.depends_on_position() { 24 } else { 12 };
    let sides = if lights.model.two_side { 2 } else { 1 };
    f64::from(read + 16 * sides)
}

/// Bytes read and written per second by a copy of 40 bytes per vertex of
/// the batch (the most a one-sided vertex moves) from one buffer to
/// another, split among the pool's threads as the kernel splits a batch:
/// the `memcpy`-like stream whose rate is the ceiling memory puts on a
/// kernel that reads its input once and writes its output once.
fn measure_copy_rate(count: usize) -> f64 {
    const FLOATS_PER_VERTEX: usize = 10;
    let len = count * FLOATS_PER_VERTEX;
    let from = vec![1.0f32; len];
    let mut to = vec![0.0f32; len];
    let chunk = len.div_ceil(4 * rayon::current_num_threads()).max(1);
    let seconds = median_seconds(|| {
        to.par_chunks_mut(chunk)
            .zip(from.par_chunks(chunk))
            .for_each(|(to, from)| to.copy_from_slice(from));
        std::hint::black_box(&mut to);
    });
    (2 * len * std::mem::size_of::<f32>()) as f64 / seconds
}

/// The name a request gives the tier.
fn tier_name(tier: Precision) -> &'static str {
    match tier {
        Precision::Reference => "reference",
        Precision::Accurate => "accurate",
        Precision::Fast => "fast",
    }
}

/// The budgets `{"max_abs_error": E}` that select `tier`: the cheapest tier
/// whose documented bound is at most `E` (the contract's rule), so from
/// its bound up to the bound of the next cheaper tier.
fn selecting_budgets(tier: Precision) -> String {
    const CHEAPEST_FIRST: [Precision; 3] =
        [Precision::Fast, Precision::Accurate, Precision::Reference];
    let at = CHEAPEST_FIRST.iter().position(|&t| t == tier).unwrap();
    let least = tier.max_abs_error();
    match at.checked_sub(1).map(|cheaper| CHEAPEST_FIRST[cheaper]) {
        None => format!("E ≥ {least:.3e}"),
        Some(cheaper) => format!("{least:.3e} ≤ E < {:.3e}", cheaper.max_abs_error()),
    }
}

/// Peak f32 FMA rate of the pool, in FLOP/s: independent multiply-adds on
/// 128 lanes, which the compiler keeps in vector registers. A multiply-add
/// waits four cycles for its operand and two issue per cycle, so a chain per
/// register needs eight registers in flight to reach the rate: 64 lanes
/// (four AVX-512 registers) measured half of it, the latency's rate rather
/// than the units'; 192 lanes measured the same as 128.
fn measure_flop_rate() -> f64 {
    const LANES: usize = 128;
    const STEPS: usize = 2_000_000;
    let threads = rayon::current_num_threads();
    let seconds = median_seconds(|| {
        (0..threads).into_par_iter().for_each(|t| {
            std::hint::black_box(fma_loop::<LANES>(STEPS, t as f32));
        })
    });
    (threads * LANES * STEPS * 2) as f64 / seconds
}

#[inline(always)]
fn fma_body<const LANES: usize>(steps: usize, seed: f32) -> f32 {
    let mut acc = [seed; LANES];
    let (a, b) = (
        std::hint::black_box(0.999_9f32),
        std::hint::black_box(1e-4f32),
    );
    for _ in 0..steps {
        for x in acc.iter_mut() {
            *x = x.mul_add(a, b);
        }
    }
    acc.iter().sum()
}

fn fma_loop<const LANES: usize>(steps: usize, seed: f32) -> f32 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
        {
            #[target_feature(enable = "avx512f,avx2,fma")]
            fn with_avx512<const LANES: usize>(steps: usize, seed: f32) -> f32 {
                fma_body::<LANES>(steps, seed)
            }
            // SAFETY: the CPU has AVX-512F, AVX2 and FMA, checked just above.
            return unsafe { with_avx512::<LANES>(steps, seed) };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            #[target_feature(enable = "avx2,fma")]
            fn with_fma<const LANES: usize>(steps: usize, seed: f32) -> f32 {
                fma_body::<LANES>(steps, seed)
            }
            // SAFETY: the CPU has AVX2 and FMA, checked just above.
            return unsafe { with_fma::<LANES>(steps, seed) };
        }
    }
    fma_body::<LANES>(steps, seed)
}

/// Vertices per second of the NumPy script per scene file, when Python with
/// NumPy is there.
fn numpy_rates(count: usize) -> Vec<(String, f64)> {
    let script = format!("{}/benches/trade_numpy.py", env!("CARGO_MANIFEST_DIR"));
    let output = Command::new("python3")
        .arg(script)
        .arg(count.to_string())
        .output();
    match output {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|line| {
                let (file, rate) = line.split_once(' ')?;
                Some((file.to_owned(), rate.trim().parse().ok()?))
            })
            .collect(),
        _ => {
            eprintln!("NumPy comparison skipped: python3 with numpy not available");
            Vec::new()
        }
    }
}

fn markdown(
    rows: &[Row],
    ceilings: &[Ceiling],
    rates: &Rates,
    numpy: &[(String, f64)],
    count: usize,
    cores: usize,
) -> String {
    let mut out = String::new();
    let cpu = common::cpu_model();
    out += &format!(
        "# The speed-for-accuracy trade\n\n\
         Made by `cargo bench --bench trade` on {cores} cores ({cpu}), {count} vertices per \
         batch; each figure is the median of at least {RUNS} runs and {MEASURE:?} of them, \
         after {WARM_UP:?} of untimed ones, `accurate` and `fast` in turns, run by run; their \
         ratios are the median, over the turns, of the ratio of the two runs' times in the \
         turn (a drift in the machine's speed moves both alike), the reference's the ratio of \
         the medians. Errors \
         are against the f64 reference, over the RGB channels of every vertex; \"8-bit\" is \
         the share of channels whose round(255·c) differs. A request's `\"precision\": \
         {{\"max_abs_error\": E}}` selects the cheapest tier whose documented bound is at most \
         E: the budgets column gives the E that select each.\n\n\
         | scene | tier | budgets that select it | ns/vertex, all cores | M vertices/s, 1 core | M vertices/s, all cores | ÷ accurate, 1 core | ÷ accurate, all cores | max error | documented bound | mean error | 8-bit channels differing |\n\
         | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n"
    );
    for r in rows {
        let accurate = find(rows, r.scene, Precision::Accurate);
        let [one_core, all_cores] = r.paired.unwrap_or([
            r.one_core / accurate.one_core,
            r.all_cores / accurate.all_cores,
        ]);
        out += &format!(
            "| {} | {} | {} | {:.2} | {:.1} | {:.1} | {:.2} | {:.2} | {:.1e} | {:.3e} | {:.1e} | {:.4}% |\n",
            r.scene,
            tier_name(r.tier),
            selecting_budgets(r.tier),
            1e9 / r.all_cores,
            r.one_core / 1e6,
            r.all_cores / 1e6,
            one_core,
            all_cores,
            r.max_error,
            r.tier.max_abs_error(),
            r.mean_error,
            r.differing_bytes * 100.0
        );
    }
    out += &format!(
        "\n## The kernel's ceilings, same run\n\n\
         The machine's f32 FMA rate, all cores: {:.1} GFLOP/s. A copy from one buffer to \
         another of 40 bytes per vertex of the batch moves {:.1} GB/s (read and written) on \
         one core, {:.1} GB/s on all. The FMA ceiling of a scene is that rate over its \
         estimated FLOPs per vertex (counted from the accurate kernel's source, and held \
         against both tiers: the fast one does the same work with fewer operations); its \
         memory ceiling is the copy's rate, all cores, over the bytes a vertex reads (f32 \
         normal, and position where the lighting uses it) and writes (an f32 RGBA colour per \
         side). The nearer ceiling limits the scene: where it is memory and `accurate` \
         already runs near it, `fast` cannot be much faster.\n\n\
         | scene | FLOPs/vertex (est.) | bytes/vertex | FMA ceiling, M vertices/s | memory ceiling, M vertices/s | accurate: share of FMA ceiling | accurate: share of memory ceiling | fast: share of FMA ceiling | fast: share of memory ceiling | limited by | NumPy, M vertices/s |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |\n",
        rates.flop / 1e9,
        rates.copy[0] / 1e9,
        rates.copy[1] / 1e9,
    );
    for (ceiling, file) in ceilings.iter().zip(common::SCENES.map(|(_, f)| f)) {
        let arithmetic = rates.flop / ceiling.flops;
        let memory = rates.copy[1] / ceiling.bytes;
        let accurate = find(rows, ceiling.scene, Precision::Accurate).all_cores;
        let fast = find(rows, ceiling.scene, Precision::Fast).all_cores;
        let numpy = numpy
            .iter()
            .find(|(f, _)| f == file)
            .map_or("not run".to_owned(), |(_, rate)| {
                format!("{:.1}", rate / 1e6)
            });
        out += &format!(
            "| {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.0}% | {:.0}% | {:.0}% | {:.0}% | {} | {numpy} |\n",
            ceiling.scene,
            ceiling.flops,
            ceiling.bytes,
            arithmetic / 1e6,
            memory / 1e6,
            100.0 * accurate / arithmetic,
            100.0 * accurate / memory,
            100.0 * fast / arithmetic,
            100.0 * fast / memory,
            if memory < arithmetic {
                "memory"
            } else {
                "arithmetic"
            },
        );
    }
    out
}

/// The row of `scene` and `tier`.
fn find<'r>(rows: &'r [Row], scene: &str, tier: Precision) -> &'r Row {
    rows.iter()
        .find(|r| r.scene == scene && r.tier == tier)
        .expect("every scene has a row per tier")
}

/// Time per vertex (all cores) against max error, log-log: a point per
/// scene and tier, each scene's tiers joined, and each tier's documented
/// bound (the least budget that selects it) as a dashed line in its
/// colour.
fn chart(rows: &[Row], path: &str) -> Result<(), Box<dyn std::error::Error>> {
    const TIERS: [(Precision, RGBColor); 3] = [
        (Precision::Reference, BLACK),
        (Precision::Accurate, BLUE),
        (Precision::Fast, RED),
    ];
    let root = SVGBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let floor = 1e-9;
    let nanoseconds = |r: &Row| 1e9 / r.all_cores;
    let mut chart = ChartBuilder::on(&root)
        .caption("glint: time against error", ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((1e-1f64..1e4f64).log_scale(), (floor..1e-1f64).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("ns per vertex, all cores")
        .y_desc("max abs error against the reference")
        .x_label_formatter(&|x| format!("{x:.0e}"))
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()?;
    for (scene, _) in common::SCENES {
        let points: Vec<(f64, f64)> = TIERS
            .iter()
            .map(|&(tier, _)| find(rows, scene, tier))
            .map(|r| (nanoseconds(r), r.max_error.max(floor)))
            .collect();
        chart.draw_series(LineSeries::new(points, BLACK.mix(0.25)))?;
    }
    for (tier, color) in TIERS {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.tier == tier)
            .map(|r| (nanoseconds(r), r.max_error.max(floor)))
            .collect();
        let bound = tier.max_abs_error();
        chart.draw_series(DashedLineSeries::new(
            [(1e-1, bound), (1e4, bound)],
            6,
            4,
            color.mix(0.6).into(),
        ))?;
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 5, color.filled())))?
            .label(format!(
                "{}: selected by {}",
                tier_name(tier),
                selecting_budgets(tier)
            ))
            .legend(move |(x, y)| Circle::new((x, y), 5, color.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

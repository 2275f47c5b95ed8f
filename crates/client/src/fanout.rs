//! The tile fan-out client behind `glint render REQ.json --via URL`: one
//! render split into `region` tiles, sent concurrently through any glint
//! URL (one replica or a load balancer in front of many), and stitched into
//! the PNG the single request would have answered, byte for byte.
//!
//! The bytes are the same because a region renders exactly the pixels it
//! has in the whole image (the kernels recentre on the scene and the eye,
//! never on the region), each tile comes back as lossless RGBA8, and the
//! stitched pixels go through the server's own encoder
//! ([`film::encode_png`]). Each tile counts against a server's pixel limit
//! on its own, so an image larger than one server's `--max-pixels` can be
//! rendered this way.
//!
//! A tile is retried when a retry may succeed: on 503 (and 429) after the
//! server's `Retry-After`, on a connection error, a timeout or another 5xx
//! after an exponential backoff with jitter, up to a bounded number of
//! tries. Renders are pure functions of their request, so a retried tile,
//! wherever it lands, renders the same pixels. Any other answer (a 4xx: the
//! request itself is wrong, or too large for the server) stops the render at
//! once: no retry would mend it.

use std::collections::BTreeMap;
use std::fmt;
use std::hash::BuildHasher;
use std::str::FromStr;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use glint_protocol::SERVED_BY;
use glint_trace::{Region, film};
use reqwest::header::{ACCEPT, CONTENT_TYPE, HeaderMap, RETRY_AFTER};

use crate::describe;
use serde::Serialize;

/// The first backoff; each further try doubles it, up to [`BACKOFF_CAP`].
const BACKOFF_FIRST: Duration = Duration::from_millis(100);
/// The longest backoff between two tries of a tile.
const BACKOFF_CAP: Duration = Duration::from_secs(5);
/// The longest `Retry-After` honoured as given; a longer one is cut to this,
/// since a later try is bounded in number anyway.
const RETRY_AFTER_CAP: Duration = Duration::from_secs(30);
/// Time to open a connection.
const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

/// A grid of `columns × rows` tiles, written `CxR` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    pub columns: u32,
    pub rows: u32,
}

impl FromStr for Grid {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (c, r) = s
            .split_once(['x', 'X', '×'])
            .ok_or_else(|| format!("`{s}` is not COLUMNSxROWS, as 4x4"))?;
        let count = |n: &str| match n.trim().parse::<u32>() {
            Ok(n) if n >= 1 => Ok(n),
            _ => Err(format!("`{n}` in `{s}` is not a count of at least 1")),
        };
        Ok(Self {
            columns: count(c)?,
            rows: count(r)?,
        })
    }
}

impl fmt::Display for Grid {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}x{}", self.columns, self.rows)
    }
}

impl Grid {
    /// The tiles of `area`, row by row from the top, each left to right:
    /// column `i` of `C` spans `[x + ⌊w·i/C⌋, x + ⌊w·(i+1)/C⌋)`, and rows
    /// alike, so that tiles differ in size by at most a pixel and cover
    /// `area` exactly. A grid finer than the area has as many columns (rows)
    /// as the area has pixels across (down), so no tile is empty.
    pub fn tiles(self, area: Region) -> Vec<Region> {
        let cuts = |start: u32, len: u32, parts: u32| -> Vec<(u32, u32)> {
            let parts = u64::from(parts.min(len));
            (0..parts)
                .map(|i| {
                    let at = |k: u64| start + (u64::from(len) * k / parts) as u32;
                    (at(i), at(i + 1) - at(i))
                })
                .collect()
        };
        let columns = cuts(area.x, area.width, self.columns);
        cuts(area.y, area.height, self.rows)
            .into_iter()
            .flat_map(|(y, height)| {
                columns.iter().map(move |&(x, width)| Region {
                    x,
                    y,
                    width,
                    height,
                })
            })
            .collect()
    }
}

/// A render request cut into tiles: the area the single request would
/// render (its `region`, or the whole image), the tiles, and the body of
/// each tile's request.
pub struct Plan {
    pub area: Region,
    pub tiles: Vec<Region>,
    /// The request without its `region`, serialised once: `{` and the rest.
    rest: Vec<u8>,
}

impl Plan {
    /// Cuts `area`, the area `request` renders, by `grid`. The caller has
    /// validated `request` as the endpoint would, and found its area, so a
    /// bad request is refused before anything is sent; a body that is not a
    /// JSON object is refused here.
    pub fn new(request: &[u8], area: Region, grid: Grid) -> Result<Self, String> {
        let mut object: serde_json::Map<String, serde_json::Value> =
            serde_json::from_slice(request)
                .map_err(|e| format!("the request is not a JSON object: {e}"))?;
        object.remove("region");
        let rest = serde_json::to_vec(&object).expect("JSON serialises");
        Ok(Self {
            area,
            tiles: grid.tiles(area),
            rest,
        })
    }

    /// The body of the request for `tile`: the request with `region` set to
    /// it (first, so the rest of the body is the same bytes for every tile).
    pub fn body(&self, tile: Region) -> Vec<u8> {
        let region = format!(
            r#"{{"region":{{"x":{},"y":{},"width":{},"height":{}}}"#,
            tile.x, tile.y, tile.width, tile.height
        );
        let mut body = region.into_bytes();
        // `rest` is `{}` or `{"…":…}`: a comma joins the region to its fields.
        if self.rest.len() > 2 {
            body.push(b',');
        }
        body.extend_from_slice(&self.rest[1..]);
        body
    }
}

/// How to fan a render out.
#[derive(Clone, Debug)]
pub struct Options {
    /// The service: `http://host:port`, to which `/v1/render` is added.
    pub via: String,
    /// Tiles in flight at once.
    pub parallel: usize,
    /// Tries of one tile, the first included.
    pub tries: u32,
    /// Time one try of a tile may take, connection included.
    pub try_timeout: Duration,
    /// Draw a progress bar on stderr (only where stderr is a terminal).
    pub progress: bool,
}

/// What a fan-out did, tile by tile.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    pub width: u32,
    pub height: u32,
    pub tiles: Vec<TileReport>,
    /// Tiles answered by each replica, as named by `x-served-by`
    /// (`unknown` for an answer without it).
    pub served_by: BTreeMap<String, usize>,
    /// Tries beyond the first, over all tiles.
    pub retries: u32,
    pub elapsed_ms: f64,
}

/// One tile of a [`Report`].
#[derive(Clone, Debug, Serialize)]
pub struct TileReport {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub served_by: Option<String>,
    pub tries: u32,
}

/// A fan-out render: the PNG, and how it was made.
pub struct Fanout {
    pub png: Vec<u8>,
    pub report: Report,
}

/// Why a fan-out render failed.
#[derive(Debug)]
pub enum FanoutError {
    /// The client cannot start: the URL is not one it can use, or no HTTP
    /// client could be made.
    Client(String),
    /// A server refused a tile in a way no retry mends (a 4xx); `body` is
    /// what it answered, a problem+json from glint.
    Refused {
        tile: Region,
        status: u16,
        body: String,
    },
    /// A tile failed every one of its tries.
    GaveUp {
        tile: Region,
        tries: u32,
        last: String,
    },
    /// A tile came back as something other than the tile it asked for.
    BadTile { tile: Region, why: String },
}

impl fmt::Display for FanoutError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let at = |t: &Region| format!("the tile {}×{} at ({}, {})", t.width, t.height, t.x, t.y);
        match self {
            Self::Client(why) => write!(f, "{why}"),
            Self::Refused { tile, status, .. } => {
                write!(f, "{} was refused with {status}", at(tile))
            }
            Self::GaveUp { tile, tries, last } => {
                write!(f, "{} failed {tries} tries; the last: {last}", at(tile))
            }
            Self::BadTile { tile, why } => write!(f, "{}: {why}", at(tile)),
        }
    }
}

impl std::error::Error for FanoutError {}

/// The outcome of one try of a tile.
enum Try {
    Done {
        rgba: Vec<u8>,
        served_by: Option<String>,
    },
    /// Worth another try, after the server's `Retry-After` when it gave one.
    Again {
        retry_after: Option<Duration>,
        why: String,
    },
    Stop(FanoutError),
}

/// A rendered tile, in the canvas's order.
struct TileDone {
    index: usize,
    rgba: Vec<u8>,
    served_by: Option<String>,
    tries: u32,
}

/// What every worker shares.
struct Shared {
    client: reqwest::Client,
    url: reqwest::Url,
    plan: Plan,
    tries: u32,
    next: AtomicUsize,
    retries: AtomicUsize,
}

/// Renders `plan` (a `/v1/render` request cut into tiles) through the
/// service at `options.via`, tile by tile, and stitches the PNG.
pub async fn render(plan: Plan, options: &Options) -> Result<Fanout, FanoutError> {
    let started = Instant::now();
    let url = render_url(&options.via)?;
    let client = reqwest::Client::builder()
        .connect_timeout(CONNECT_TIMEOUT.min(options.try_timeout))
        .timeout(options.try_timeout)
        .pool_max_idle_per_host(options.parallel)
        .build()
        .map_err(|e| FanoutError::Client(format!("cannot make an HTTP client: {e}")))?;
    let total = plan.tiles.len();
    let area = plan.area;
    let shared = Arc::new(Shared {
        client,
        url,
        plan,
        tries: options.tries.max(1),
        next: AtomicUsize::new(0),
        retries: AtomicUsize::new(0),
    });

    let progress = Progress::new(options.progress, total);
    let (done_tx, mut done_rx) = tokio::sync::mpsc::channel(options.parallel.max(1));
    // Dropped on return, which aborts every worker still running: a failed
    // tile stops the render.
    let mut workers = tokio::task::JoinSet::new();
    for _ in 0..options.parallel.clamp(1, total) {
        let (shared, done) = (shared.clone(), done_tx.clone());
        workers.spawn(async move {
            loop {
                let index = shared.next.fetch_add(1, Ordering::Relaxed);
                let Some(&tile) = shared.plan.tiles.get(index) else {
                    return;
                };
                let result = render_tile(&shared, index, tile).await;
                if done.send(result).await.is_err() {
                    return;
                }
            }
        });
    }
    drop(done_tx);

    let (width, height) = (area.width as usize, area.height as usize);
    let mut canvas = vec![0u8; width * height * 4];
    let mut reports: Vec<Option<TileReport>> = vec![None; total];
    while let Some(result) = done_rx.recv().await {
        let done = result?;
        let tile = shared.plan.tiles[done.index];
        // Row by row into the canvas, at the tile's place in the area.
        let row = tile.width as usize * 4;
        for (k, line) in done.rgba.chunks_exact(row).enumerate() {
            let y = (tile.y - area.y) as usize + k;
            let start = (y * width + (tile.x - area.x) as usize) * 4;
            canvas[start..start + row].copy_from_slice(line);
        }
        reports[done.index] = Some(TileReport {
            x: tile.x,
            y: tile.y,
            width: tile.width,
            height: tile.height,
            served_by: done.served_by,
            tries: done.tries,
        });
        progress.tile_done(shared.retries.load(Ordering::Relaxed));
    }
    drop(progress);

    let tiles: Vec<TileReport> = reports
        .into_iter()
        .map(|r| r.expect("every tile was rendered, or the render failed"))
        .collect();
    let mut served_by = BTreeMap::new();
    for tile in &tiles {
        let name = tile.served_by.clone().unwrap_or_else(|| "unknown".into());
        *served_by.entry(name).or_insert(0) += 1;
    }
    Ok(Fanout {
        png: film::encode_png(area.width, area.height, &canvas),
        report: Report {
            width: area.width,
            height: area.height,
            retries: tiles.iter().map(|t| t.tries - 1).sum(),
            tiles,
            served_by,
            elapsed_ms: started.elapsed().as_secs_f64() * 1e3,
        },
    })
}

/// `{via}/v1/render`, for an `http` URL.
fn render_url(via: &str) -> Result<reqwest::Url, FanoutError> {
    let base = reqwest::Url::parse(via)
        .map_err(|e| FanoutError::Client(format!("`{via}` is not a URL: {e}")))?;
    if base.scheme() != "http" {
        return Err(FanoutError::Client(format!(
            "`{via}`: the fan-out client speaks plain HTTP (http://host:port), \
             as to replicas or a load balancer inside one network"
        )));
    }
    let path = format!(
        "{}{}",
        base.path().trim_end_matches('/'),
        glint_protocol::RENDER
    );
    let mut url = base;
    url.set_path(&path);
    Ok(url)
}

/// Tries `tile` until it renders, a try says stop, or the tries run out.
async fn render_tile(shared: &Shared, index: usize, tile: Region) -> Result<TileDone, FanoutError> {
    let body = shared.plan.body(tile);
    let mut last = String::new();
    for attempt in 1..=shared.tries {
        if attempt > 1 {
            shared.retries.fetch_add(1, Ordering::Relaxed);
        }
        match try_tile(shared, tile, body.clone()).await {
            Try::Done { rgba, served_by } => {
                return Ok(TileDone {
                    index,
                    rgba,
                    served_by,
                    tries: attempt,
                });
            }
            Try::Stop(error) => return Err(error),
            Try::Again { retry_after, why } => {
                last = why;
                if attempt < shared.tries {
                    let wait = retry_after.unwrap_or_else(|| backoff(index, attempt));
                    tokio::time::sleep(wait).await;
                }
            }
        }
    }
    Err(FanoutError::GaveUp {
        tile,
        tries: shared.tries,
        last,
    })
}

/// One try of `tile`.
async fn try_tile(shared: &Shared, tile: Region, body: Vec<u8>) -> Try {
    let sent = shared
        .client
        .post(shared.url.clone())
        .header(CONTENT_TYPE, "application/json")
        .header(ACCEPT, "image/png")
        .body(body)
        .send()
        .await;
    let response = match sent {
        Ok(response) => response,
        // Refused, reset, timed out: the replica may be gone; another may answer.
        Err(e) => {
            return Try::Again {
                retry_after: None,
                why: describe(&e),
            };
        }
    };
    let status = response.status();
    let served_by = response
        .headers()
        .get(SERVED_BY)
        .and_then(|v| v.to_str().ok())
        .map(str::to_owned);
    let retry_after = retry_after(response.headers());
    let bytes = match response.bytes().await {
        Ok(bytes) => bytes,
        // Cut off mid-body: as a connection error.
        Err(e) => {
            return Try::Again {
                retry_after: None,
                why: describe(&e),
            };
        }
    };
    let said = || {
        format!(
            "{status} from {}: {}",
            served_by.as_deref().unwrap_or("a server"),
            String::from_utf8_lossy(&bytes[..bytes.len().min(300)])
        )
    };
    match status.as_u16() {
        200 => match decode(&bytes, tile) {
            Ok(rgba) => Try::Done { rgba, served_by },
            Err(why) => Try::Stop(FanoutError::BadTile { tile, why }),
        },
        429 | 503 => Try::Again {
            retry_after,
            why: said(),
        },
        408 | 500..=599 => Try::Again {
            retry_after: None,
            why: said(),
        },
        code => Try::Stop(FanoutError::Refused {
            tile,
            status: code,
            body: String::from_utf8_lossy(&bytes).into_owned(),
        }),
    }
}

/// The RGBA8 pixels of a tile's PNG, which must be the tile's size.
fn decode(png: &[u8], tile: Region) -> Result<Vec<u8>, String> {
    let image = image::load_from_memory_with_format(png, image::ImageFormat::Png)
        .map_err(|e| format!("the answer is not a PNG: {e}"))?;
    let image::DynamicImage::ImageRgba8(rgba) = image else {
        return Err(format!("the PNG is {:?}, not RGBA8", image.color()));
    };
    if rgba.dimensions() != (tile.width, tile.height) {
        let (w, h) = rgba.dimensions();
        return Err(format!("the PNG is {w}×{h}"));
    }
    Ok(rgba.into_raw())
}

/// A `Retry-After` in seconds (the form glint sends), at most
/// [`RETRY_AFTER_CAP`]; `None` for none or for the HTTP-date form, which
/// then gets the usual backoff.
fn retry_after(headers: &HeaderMap) -> Option<Duration> {
    let seconds: u64 = headers
        .get(RETRY_AFTER)?
        .to_str()
        .ok()?
        .trim()
        .parse()
        .ok()?;
    Some(Duration::from_secs(seconds).min(RETRY_AFTER_CAP))
}

/// The wait before try `attempt + 1` of tile `index`: `BACKOFF_FIRST ·
/// 2^(attempt-1)`, at most [`BACKOFF_CAP`], half of it fixed and half
/// drawn at random ("equal jitter"), so that tiles that failed together do
/// not all come back together.
pub fn backoff(index: usize, attempt: u32) -> Duration {
    let doubled = BACKOFF_FIRST.saturating_mul(1u32 << attempt.saturating_sub(1).min(16));
    let ceiling = doubled.min(BACKOFF_CAP);
    let random = std::collections::hash_map::RandomState::new().hash_one((index, attempt));
    let half = ceiling / 2;
    half + half.mul_f64((random >> 11) as f64 / (1u64 << 53) as f64)
}

/// A progress bar of tiles on stderr, drawn only on a terminal, and cleared
/// when dropped.
struct Progress(indicatif::ProgressBar);

impl Progress {
    fn new(wanted: bool, tiles: usize) -> Self {
        use std::io::IsTerminal;
        if !(wanted && std::io::stderr().is_terminal()) {
            return Self(indicatif::ProgressBar::hidden());
        }
        let bar = indicatif::ProgressBar::new(tiles as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed:>4} [{bar:32}] {pos}/{len} tiles {msg}",
            )
            .expect("a valid template")
            .progress_chars("=> "),
        );
        Self(bar)
    }

    fn tile_done(&self, retries: usize) {
        if retries > 0 {
            self.0.set_message(format!("({retries} retried)"));
        }
        self.0.inc(1);
    }
}

impl Drop for Progress {
    /// The bar leaves no trace, whether the render succeeded or not.
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(x: u32, y: u32, width: u32, height: u32) -> Region {
        Region {
            x,
            y,
            width,
            height,
        }
    }

    #[test]
    fn tiles_cover_the_area_exactly_once() {
        for (grid, a) in [
            ("4x4", area(0, 0, 64, 48)),
            ("3x2", area(5, 7, 10, 11)),
            ("7x5", area(0, 0, 3840, 2160)),
            ("9x9", area(2, 3, 4, 5)),
            ("1x1", area(0, 0, 1, 1)),
        ] {
            let grid: Grid = grid.parse().unwrap();
            let tiles = grid.tiles(a);
            let mut covered = vec![0u8; (a.width * a.height) as usize];
            for t in &tiles {
                assert!(t.width >= 1 && t.height >= 1, "{grid}: empty tile {t:?}");
                for y in t.y..t.y + t.height {
                    for x in t.x..t.x + t.width {
                        covered[((y - a.y) * a.width + (x - a.x)) as usize] += 1;
                    }
                }
            }
            assert!(covered.iter().all(|&c| c == 1), "{grid} over {a:?}");
            let expected = grid.columns.min(a.width) * grid.rows.min(a.height);
            assert_eq!(tiles.len(), expected as usize, "{grid} over {a:?}");
        }
    }

    #[test]
    fn grids_parse_as_columns_by_rows() {
        assert_eq!(
            "4x3".parse::<Grid>(),
            Ok(Grid {
                columns: 4,
                rows: 3
            })
        );
        assert_eq!(
            "2×5".parse::<Grid>(),
            Ok(Grid {
                columns: 2,
                rows: 5
            })
        );
        for bad in ["4", "0x2", "x", "4x-1", "axb"] {
            assert!(bad.parse::<Grid>().is_err(), "{bad}");
        }
    }

    #[test]
    fn a_tile_body_is_the_request_with_its_region() {
        let request = br#"{"camera":{"eye":[0,0,5],"target":[0,0,0],"up":[0,1,0],"fov_y":45,"width":8,"height":6},"region":{"x":2,"y":1,"width":6,"height":5},"materials":{},"objects":[]}"#;
        let plan = Plan::new(request, area(2, 1, 6, 5), "2x1".parse().unwrap()).unwrap();
        assert_eq!(plan.area, area(2, 1, 6, 5));
        assert_eq!(plan.tiles, vec![area(2, 1, 3, 5), area(5, 1, 3, 5)]);
        let body: serde_json::Value = serde_json::from_slice(&plan.body(plan.tiles[1])).unwrap();
        let mut expected: serde_json::Value = serde_json::from_slice(request).unwrap();
        expected["region"] = serde_json::json!({"x": 5, "y": 1, "width": 3, "height": 5});
        assert_eq!(body, expected);
    }

    #[test]
    fn backoff_doubles_within_its_cap_with_half_of_it_random() {
        for attempt in 1..=12 {
            let ceiling = (BACKOFF_FIRST * 2u32.pow(attempt - 1)).min(BACKOFF_CAP);
            let wait = backoff(3, attempt);
            assert!(
                wait >= ceiling / 2 && wait <= ceiling,
                "{attempt}: {wait:?}"
            );
        }
    }

    #[test]
    fn only_http_urls_are_taken() {
        assert_eq!(
            render_url("http://127.0.0.1:8080").unwrap().as_str(),
            "http://127.0.0.1:8080/v1/render"
        );
        assert_eq!(
            render_url("http://lb/glint/").unwrap().as_str(),
            "http://lb/glint/v1/render"
        );
        assert!(render_url("https://lb").is_err());
        assert!(render_url("lb:8080").is_err());
    }
}

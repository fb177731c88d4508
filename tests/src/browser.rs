//! A page opened in headless Chromium (Debian's `chromium` package, `/usr/bin/chromium`): a screenshot, decoded and
//! checked not to be blank, and the page's console messages, of which there must be none.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Where Debian's package installs the browser.
pub const CHROMIUM: &str = "/usr/bin/chromium";
/// The longest a page may take to load and be captured.
const PAGE_TIMEOUT: Duration = Duration::from_secs(90);

/// What the browser saw.
#[derive(Debug)]
pub struct PageShot {
    /// Console messages of the page (errors, warnings, logs), as Chromium logs them.
    pub console: Vec<String>,
    /// Width and height of the screenshot, pixels.
    pub size: (u32, u32),
    /// Variance of the screenshot's luminance (0: a single colour).
    pub luminance_variance: f64,
    /// Share of pixels that are not white.
    pub ink: f64,
}

/// Opens `page` (a file) in headless Chromium with a fresh profile and no network, takes a `width` x `height`
/// screenshot and collects the console. Panics, saying how to get it, if Chromium is not installed.
pub fn open(page: &Path, (width, height): (u32, u32)) -> PageShot {
    assert!(
        Path::new(CHROMIUM).exists(),
        "{CHROMIUM} is missing: this test opens report.html in headless Chromium. The README's test command \
         installs it (Debian: `apt-get install -y chromium`)"
    );
    let profile = tempfile::tempdir().expect("a temporary profile folder");
    let shot: PathBuf = profile.path().join("shot.png");
    let page = page.canonicalize().expect("the page exists");
    let mut child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.path().join("profile").display()))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("--window-size={width},{height}"))
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("chromium starts");
    // Read stderr on a thread so that a chatty browser never blocks on a full pipe.
    let mut stderr = child.stderr.take().expect("piped");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut s);
        s
    });
    let deadline = Instant::now() + PAGE_TIMEOUT;
    let status = loop {
        if let Some(status) = child.try_wait().expect("chromium runs") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within {PAGE_TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let log = reader.join().expect("the stderr reader");
    assert!(status.success(), "chromium failed ({status}):\n{log}");
    let console = log.lines().filter(|l| l.contains(":CONSOLE")).map(str::to_string).collect();
    let (size, luminance_variance, ink) = measure(&shot);
    PageShot { console, size, luminance_variance, ink }
}

/// Size, luminance variance and share of non-white pixels of a PNG.
fn measure(path: &Path) -> ((u32, u32), f64, f64) {
    let file =
        std::fs::File::open(path).unwrap_or_else(|e| panic!("no screenshot at {}: {e}", path.display()));
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    let channels = info.color_type.samples();
    let lum: Vec<f64> = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| match channels {
            1 | 2 => f64::from(p[0]),
            _ => 0.299 * f64::from(p[0]) + 0.587 * f64::from(p[1]) + 0.114 * f64::from(p[2]),
        })
        .collect();
    let n = lum.len().max(1) as f64;
    let mean = lum.iter().sum::<f64>() / n;
    let variance = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n;
    let ink = lum.iter().filter(|l| **l < 250.0).count() as f64 / n;
    ((info.width, info.height), variance, ink)
}

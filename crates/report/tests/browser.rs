//! Issue 11, acceptance 3: a run's report in a real headless Chromium
//! (Debian's `chromium`, driven over the DevTools protocol). The page is
//! loaded from `file://`; the test fails on any console error or uncaught
//! exception, on any request that is not the page itself (or an in-memory
//! `data:`/`blob:` URL), when a plot is missing, and when the WebGL 3-D view
//! has not drawn coloured pixels. A screenshot is kept beside the report.
//!
//! Needs a run folder written by `surveyor explore` in `SURVEYOR_REPORT_RUN`
//! and one written by `surveyor follow` in `SURVEYOR_REPORT_FOLLOW_RUN`
//! (`.ci/run` makes both), and Chromium at `/usr/bin/chromium` or `$CHROME`:
//!
//! ```text
//! cargo run --release -- explore --scenario bridge1 --out /tmp/run
//! SURVEYOR_REPORT_RUN=/tmp/run cargo test -p report --test browser explore -- --ignored --nocapture
//! cargo run --release -- follow --scenario block1 --robot arm4 --out /tmp/follow
//! SURVEYOR_REPORT_FOLLOW_RUN=/tmp/follow cargo test -p report --test browser follow -- --ignored --nocapture
//! ```

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test: the checks shared by both tests sit in helper functions, which \
              allow-unwrap-in-tests does not cover"
)]

use headless_chrome::protocol::cdp::types::Event;
use headless_chrome::protocol::cdp::{Log, Network, Page, Runtime};
use headless_chrome::{Browser, LaunchOptions};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The plots an explore report must hold.
const EXPLORE_PLOTS: [&str; 9] = [
    "plot-view3d",
    "plot-f1",
    "plot-f2",
    "plot-f3",
    "plot-f4",
    "plot-information",
    "plot-prediction",
    "plot-coverage",
    "plot-timings",
];

/// The plots every follow report holds; one `plot-evolution-<sets>` per
/// snapshot of `model_snapshots.json` comes beside them.
const FOLLOW_PLOTS: [&str; 4] = ["plot-view3d", "plot-modes", "plot-times", "plot-sensing"];

fn eval_u64(tab: &headless_chrome::Tab, js: &str) -> u64 {
    tab.evaluate(js, false)
        .unwrap_or_else(|e| panic!("`{js}`: {e}"))
        .value
        .and_then(|v| v.as_u64())
        .unwrap_or_else(|| panic!("`{js}` did not give a number"))
}

#[test]
#[ignore = "needs Chromium and SURVEYOR_REPORT_RUN=<explore run folder>; run by .ci/run"]
fn explore_report_renders_offline_in_chromium() {
    let run = run_folder(
        "SURVEYOR_REPORT_RUN",
        "set SURVEYOR_REPORT_RUN to a folder written by `surveyor explore` (see this file's header)",
    );
    check_report_in_chromium(&run, &EXPLORE_PLOTS.map(str::to_owned));
}

#[test]
#[ignore = "needs Chromium and SURVEYOR_REPORT_FOLLOW_RUN=<follow run folder>; run by .ci/run"]
fn follow_report_renders_offline_in_chromium() {
    let run = run_folder(
        "SURVEYOR_REPORT_FOLLOW_RUN",
        "set SURVEYOR_REPORT_FOLLOW_RUN to a folder written by `surveyor follow` (see this file's header)",
    );
    let snapshots: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("model_snapshots.json")).unwrap())
            .unwrap();
    let sets: Vec<u64> = snapshots["snapshots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["sets"].as_u64().unwrap())
        .collect();
    assert!(sets.len() >= 2, "too few snapshots: {sets:?}");
    let mut expected: Vec<String> = FOLLOW_PLOTS.map(str::to_owned).to_vec();
    expected.extend(sets.iter().map(|s| format!("plot-evolution-{s}")));
    check_report_in_chromium(&run, &expected);
}

/// The run folder named by the environment variable `var`. Cargo runs this
/// test in the package's folder, so a relative path that is not there is
/// taken from the workspace root (where `.ci/run` makes the runs).
fn run_folder(var: &str, missing: &str) -> PathBuf {
    let given = PathBuf::from(std::env::var_os(var).expect(missing));
    if given.is_relative() && !given.exists() {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(given)
    } else {
        given
    }
}

/// Write the report of `run`, load it in headless Chromium and check it:
/// exactly the plots `expected` (div ids) drawn, `plot-view3d` a WebGL view
/// with coloured pixels, no console error, no request but the page; keeps
/// `run/report_screenshot.png`.
fn check_report_in_chromium(run: &Path, expected_ids: &[String]) {
    let html = report::write(run).unwrap();
    let size_mb = std::fs::metadata(&html).unwrap().len() as f64 / 1e6;
    let chrome = std::env::var_os("CHROME")
        .map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    assert!(
        chrome.exists(),
        "no Chromium at {} (apt-get install chromium, or set CHROME)",
        chrome.display()
    );
    let profile = tempfile::tempdir().unwrap();
    let args: Vec<&OsStr> = [
        // WebGL on the CPU: this machine has no GPU.
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-component-update",
        "--disable-quic",
    ]
    .into_iter()
    .map(OsStr::new)
    .collect();
    let browser = Browser::new(LaunchOptions {
        headless: true,
        sandbox: false,
        enable_gpu: true,
        window_size: Some((1400, 2400)),
        path: Some(chrome),
        user_data_dir: Some(profile.path().to_path_buf()),
        args,
        idle_browser_timeout: Duration::from_secs(300),
        ..LaunchOptions::default()
    })
    .unwrap();
    let tab = browser.new_tab().unwrap();
    tab.set_default_timeout(Duration::from_secs(300));

    let errors = Arc::new(Mutex::new(Vec::<String>::new()));
    let requests = Arc::new(Mutex::new(Vec::<String>::new()));
    {
        let errors = errors.clone();
        let requests = requests.clone();
        tab.add_event_listener(Arc::new(move |event: &Event| match event {
            Event::RuntimeConsoleAPICalled(e) => {
                use Runtime::ConsoleAPICalledEventTypeOption as T;
                if matches!(e.params.Type, T::Error | T::Assert) {
                    let text: Vec<String> = e
                        .params
                        .args
                        .iter()
                        .map(|a| {
                            a.value
                                .as_ref()
                                .map(ToString::to_string)
                                .or_else(|| a.description.clone())
                                .unwrap_or_default()
                        })
                        .collect();
                    errors
                        .lock()
                        .unwrap()
                        .push(format!("console.error: {}", text.join(" ")));
                }
            }
            Event::RuntimeExceptionThrown(e) => {
                errors
                    .lock()
                    .unwrap()
                    .push(format!("exception: {}", e.params.exception_details.text));
            }
            Event::LogEntryAdded(e) => {
                if matches!(e.params.entry.level, Log::LogEntryLevel::Error) {
                    errors
                        .lock()
                        .unwrap()
                        .push(format!("log: {}", e.params.entry.text));
                }
            }
            Event::NetworkRequestWillBeSent(e) => {
                requests.lock().unwrap().push(e.params.request.url.clone());
            }
            _ => {}
        }))
        .unwrap();
    }
    tab.enable_runtime().unwrap();
    tab.enable_log().unwrap();
    tab.call_method(Network::Enable {
        max_total_buffer_size: None,
        max_resource_buffer_size: None,
        max_post_data_size: None,
        report_direct_socket_traffic: None,
        enable_durable_messages: None,
    })
    .unwrap();

    let url = format!("file://{}", std::fs::canonicalize(&html).unwrap().display());
    let t = Instant::now();
    tab.navigate_to(&url)
        .unwrap()
        .wait_until_navigated()
        .unwrap();
    // Every plot div becomes a plotly graph once plotly.js has drawn it.
    let expected = expected_ids.len() as u64;
    let deadline = Instant::now() + Duration::from_secs(300);
    let mut drawn = 0;
    while Instant::now() < deadline {
        drawn = eval_u64(
            &tab,
            "document.querySelectorAll('div.plot .js-plotly-plot .main-svg').length > 0 ? document.querySelectorAll('div.plot > .js-plotly-plot').length : 0",
        );
        if drawn >= expected {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let load_s = t.elapsed().as_secs_f64();
    for id in expected_ids {
        let present = eval_u64(
            &tab,
            &format!("document.querySelectorAll('#{id}.js-plotly-plot .main-svg').length"),
        );
        assert!(
            present > 0,
            "plot {id} missing or not drawn ({drawn} of {expected} drawn)"
        );
    }
    assert_eq!(
        eval_u64(&tab, "document.querySelectorAll('div.plot').length"),
        expected,
        "the page has other plots than the ones checked"
    );
    // The 3-D view is WebGL: a canvas exists and plotly did not fall back to
    // its "WebGL is not supported" notice.
    assert!(
        eval_u64(
            &tab,
            "document.querySelectorAll('#plot-view3d canvas').length"
        ) > 0
    );
    assert_eq!(
        eval_u64(
            &tab,
            "document.body.innerText.includes('WebGL is not supported') ? 1 : 0"
        ),
        0,
        "plotly found no WebGL"
    );
    std::thread::sleep(Duration::from_millis(1500));

    // Pixels of the 3-D view, cut from a screenshot of the window with the
    // view scrolled to its top (below a long summary table it may start
    // under the window's bottom edge; an element screenshot of such an
    // element captures the wrong region).
    tab.evaluate(
        "document.getElementById('plot-view3d').scrollIntoView({block: 'start'})",
        false,
    )
    .unwrap();
    std::thread::sleep(Duration::from_secs(1));
    let rect: Vec<usize> = tab
        .evaluate(
            "(() => { const r = document.getElementById('plot-view3d').getBoundingClientRect(); \
             return [r.left, r.top, r.width, r.height].map(v => Math.max(0, Math.round(v))).join(','); })()",
            false,
        )
        .unwrap()
        .value
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let shot = tab
        .capture_screenshot(Page::CaptureScreenshotFormatOption::Png, None, None, true)
        .unwrap();
    let decoder = png::Decoder::new(std::io::Cursor::new(&shot));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    // The view's left 70 % (the legend is on the right) must be far from
    // blank: the axes' grid lines alone darken a few per cent of it; the
    // model, mesh, discs, paths cover much more.
    let (x0, y0) = (rect[0].min(w), rect[1].min(h));
    let (x1, y1) = (
        (rect[0] + rect[2] * 7 / 10).min(w),
        (rect[1] + rect[3]).min(h),
    );
    let mut drawn_px = 0usize;
    let mut total = 0usize;
    for y in y0..y1 {
        for x in x0..x1 {
            let p = &buf[(y * w + x) * channels..(y * w + x) * channels + 3];
            let (lo, hi) = (p.iter().min().unwrap(), p.iter().max().unwrap());
            total += 1;
            if *lo < 200 || hi - lo > 40 {
                drawn_px += 1;
            }
        }
    }
    assert!(
        total > 100_000,
        "the 3-D view is not in the window: {rect:?} in {w}×{h}"
    );
    let share = drawn_px as f64 / total as f64;

    let shot_path = run.join("report_screenshot.png");
    std::fs::write(&shot_path, shot).unwrap();
    println!(
        "report {} ({size_mb:.1} MB): {drawn} plots drawn in {load_s:.2} s; 3-D view {:.1} % non-background pixels; screenshot {}",
        html.display(),
        100.0 * share,
        shot_path.display()
    );
    // A view with its axes but almost no data measured 3.2 %; the bridge1
    // explore view 26.5 %, the block1 follow view 12.1 %.
    assert!(
        share > 0.08,
        "the WebGL view drew little beyond its axes: {:.2} % non-background pixels",
        100.0 * share
    );

    let errors = errors.lock().unwrap();
    assert!(errors.is_empty(), "console errors: {errors:#?}");
    let requests = requests.lock().unwrap();
    let foreign: Vec<&String> = requests
        .iter()
        .filter(|u| **u != url && !u.starts_with("data:") && !u.starts_with("blob:"))
        .collect();
    assert!(
        foreign.is_empty(),
        "requests other than the page: {foreign:#?}"
    );
    assert!(
        requests.contains(&url),
        "the page load itself was not seen: {requests:?}"
    );
}

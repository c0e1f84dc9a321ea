//! Issue 11, acceptance 3: a run's report in a real headless Chromium
//! (Debian's `chromium`, driven over the DevTools protocol on a pipe). The page is
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
//! SURVEYOR_REPORT_RUN=/tmp/run cargo test -p report --test it browser explore -- --ignored --nocapture
//! cargo run --release -- follow --scenario block1 --robot arm4 --out /tmp/follow
//! SURVEYOR_REPORT_FOLLOW_RUN=/tmp/follow cargo test -p report --test it browser follow -- --ignored --nocapture
//! ```

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test: the checks shared by both tests sit in helper functions, which \
              allow-unwrap-in-tests does not cover"
)]

use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// The plots an explore report must hold.
const EXPLORE_PLOTS: [&str; 10] = [
    "plot-view3d",
    "plot-f1",
    "plot-f2",
    "plot-f3",
    "plot-f4",
    "plot-information",
    "plot-prediction",
    "plot-coverage",
    "plot-timings",
    "plot-materials",
];

/// The plots every follow report holds; one `plot-evolution-<sets>` per
/// snapshot of `model_snapshots.json` comes beside them.
const FOLLOW_PLOTS: [&str; 4] = ["plot-view3d", "plot-modes", "plot-times", "plot-sensing"];

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

/// Chromium driven over the DevTools protocol on a pipe
/// (`--remote-debugging-pipe`: commands in on file descriptor 3, replies and
/// events out on 4, each a JSON message ended by a NUL byte). `sh` hands our
/// stdin and stdout to the browser as those two descriptors.
struct DevTools {
    child: Child,
    to_browser: ChildStdin,
    from_browser: Receiver<Value>,
    next_id: u64,
    /// The page's session (Target.attachToTarget, flattened).
    session: Option<String>,
    /// Every event received so far, in order.
    events: Vec<Value>,
    /// Chromium's profile folder; its log is `chromium.log` there.
    profile: tempfile::TempDir,
}

impl DevTools {
    fn launch(chrome: &Path) -> Self {
        let profile = tempfile::tempdir().unwrap();
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(r#"exec "$0" "$@" 3<&0 4>&1 0</dev/null 1>/dev/null"#)
            .arg(chrome)
            .args([
                "--headless",
                "--remote-debugging-pipe",
                "--no-sandbox",
                // WebGL on the CPU: this machine has no GPU.
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--disable-component-update",
                "--disable-background-networking",
                "--disable-sync",
                "--disable-quic",
                "--no-first-run",
                "--window-size=1400,2400",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .arg("about:blank")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(std::fs::File::create(profile.path().join("chromium.log")).unwrap())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", chrome.display()));
        let to_browser = child.stdin.take().unwrap();
        let mut reader = BufReader::new(child.stdout.take().unwrap());
        let (tx, from_browser) = mpsc::channel();
        std::thread::spawn(move || {
            let mut message = Vec::new();
            while reader.read_until(0, &mut message).unwrap_or(0) > 0 {
                if message.last() == Some(&0) {
                    message.pop();
                }
                let value: Value = serde_json::from_slice(&message)
                    .unwrap_or_else(|e| panic!("DevTools sent no JSON ({e})"));
                if tx.send(value).is_err() {
                    break;
                }
                message.clear();
            }
        });
        let mut devtools = Self {
            child,
            to_browser,
            from_browser,
            next_id: 0,
            session: None,
            events: Vec::new(),
            profile,
        };
        let target = devtools.browser_call("Target.createTarget", &json!({"url": "about:blank"}));
        let target_id = target["targetId"].as_str().unwrap().to_owned();
        let attached = devtools.browser_call(
            "Target.attachToTarget",
            &json!({"targetId": target_id, "flatten": true}),
        );
        devtools.session = Some(attached["sessionId"].as_str().unwrap().to_owned());
        devtools
    }

    /// A command to the browser itself.
    fn browser_call(&mut self, method: &str, params: &Value) -> Value {
        self.send(method, params, None)
    }

    /// A command to the page.
    fn call(&mut self, method: &str, params: &Value) -> Value {
        let session = self.session.clone();
        self.send(method, params, session)
    }

    fn send(&mut self, method: &str, params: &Value, session: Option<String>) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({"id": id, "method": method, "params": params});
        if let Some(session) = session {
            message["sessionId"] = Value::String(session);
        }
        let mut bytes = serde_json::to_vec(&message).unwrap();
        bytes.push(0);
        if let Err(e) = self
            .to_browser
            .write_all(&bytes)
            .and_then(|()| self.to_browser.flush())
        {
            panic!("cannot send {method}: {e}; {}", self.last_words());
        }
        let deadline = Instant::now() + Duration::from_secs(300);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let reply = self
                .from_browser
                .recv_timeout(left)
                .unwrap_or_else(|e| panic!("no reply to {method}: {e}; {}", self.last_words()));
            if reply["id"].as_u64() == Some(id) {
                assert!(reply.get("error").is_none(), "{method}: {}", reply["error"]);
                return reply["result"].clone();
            }
            if reply.get("method").is_some() {
                self.events.push(reply);
            }
        }
    }

    /// The last lines of Chromium's log, for a failure message.
    fn last_words(&self) -> String {
        let log =
            std::fs::read_to_string(self.profile.path().join("chromium.log")).unwrap_or_default();
        let tail: Vec<&str> = log.lines().rev().take(20).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        format!("Chromium's last words:\n{}", tail.join("\n"))
    }

    /// The value of a JavaScript expression in the page.
    fn eval(&mut self, js: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            &json!({"expression": js, "returnByValue": true, "awaitPromise": true}),
        );
        assert!(
            r.get("exceptionDetails").is_none(),
            "`{js}` threw: {}",
            r["exceptionDetails"]
        );
        r["result"]["value"].clone()
    }

    fn eval_u64(&mut self, js: &str) -> u64 {
        self.eval(js)
            .as_u64()
            .unwrap_or_else(|| panic!("`{js}` did not give a number"))
    }
}

impl Drop for DevTools {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Write the report of `run`, load it in headless Chromium and check it:
/// exactly the plots `expected` (div ids) drawn, `plot-view3d` a WebGL view
/// with coloured pixels, no console error, no request but the page; keeps
/// `run/report_screenshot.png`.
#[allow(
    clippy::too_many_lines,
    reason = "one browser session, step by step: load, wait for the plots, read the logs, screenshot, count pixels"
)]
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
    let mut tab = DevTools::launch(&chrome);
    for domain in ["Runtime", "Log", "Network", "Page"] {
        tab.call(&format!("{domain}.enable"), &json!({}));
    }

    let url = format!("file://{}", std::fs::canonicalize(&html).unwrap().display());
    let t = Instant::now();
    tab.call("Page.navigate", &json!({"url": url}));
    // Every plot div becomes a plotly graph once plotly.js has drawn it.
    let expected = expected_ids.len() as u64;
    let deadline = Instant::now() + Duration::from_secs(300);
    let mut drawn = 0;
    while Instant::now() < deadline {
        drawn = tab.eval_u64(
            "document.querySelectorAll('div.plot .js-plotly-plot .main-svg').length > 0 ? document.querySelectorAll('div.plot > .js-plotly-plot').length : 0",
        );
        if drawn >= expected {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    let load_s = t.elapsed().as_secs_f64();
    for id in expected_ids {
        let present = tab.eval_u64(&format!(
            "document.querySelectorAll('#{id}.js-plotly-plot .main-svg').length"
        ));
        assert!(
            present > 0,
            "plot {id} missing or not drawn ({drawn} of {expected} drawn)"
        );
    }
    assert_eq!(
        tab.eval_u64("document.querySelectorAll('div.plot').length"),
        expected,
        "the page has other plots than the ones checked"
    );
    // Issue 48: the summary cards come first and hold the run's figures as
    // its run.json does, each shown with its value.
    let run_json: Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    let cards = tab.eval(
        "JSON.stringify([...document.querySelectorAll('#summary-cards .card')].map(c => \
         [c.dataset.key, c.dataset.value, c.querySelector('.card-value').innerText, \
         c.getBoundingClientRect().top < document.querySelector('h2').getBoundingClientRect().top]))",
    );
    let cards: Vec<(String, String, String, bool)> =
        serde_json::from_str(cards.as_str().unwrap()).unwrap();
    assert!(cards.len() >= 6, "too few summary cards: {cards:?}");
    for (key, value, shown, first) in &cards {
        let held = key
            .split('.')
            .try_fold(&run_json, |v, p| v.get(p))
            .unwrap_or_else(|| panic!("card {key} is not in run.json"));
        let value: Value = serde_json::from_str(value).unwrap();
        assert_eq!(held, &value, "card {key}");
        assert!(!shown.trim().is_empty() && *first, "card {key}: {shown:?}");
    }
    // The 3-D view is WebGL: a canvas exists and plotly did not fall back to
    // its "WebGL is not supported" notice.
    assert!(tab.eval_u64("document.querySelectorAll('#plot-view3d canvas').length") > 0);
    assert_eq!(
        tab.eval_u64("document.body.innerText.includes('WebGL is not supported') ? 1 : 0"),
        0,
        "plotly found no WebGL"
    );
    std::thread::sleep(Duration::from_millis(1500));

    // Pixels of the 3-D view, cut from a screenshot of the window with the
    // view scrolled to its top (below a long summary table it may start
    // under the window's bottom edge; an element screenshot of such an
    // element captures the wrong region).
    tab.eval("document.getElementById('plot-view3d').scrollIntoView({block: 'start'})");
    std::thread::sleep(Duration::from_secs(1));
    let rect: Vec<usize> = tab
        .eval(
            "(() => { const r = document.getElementById('plot-view3d').getBoundingClientRect(); \
             return [r.left, r.top, r.width, r.height].map(v => Math.max(0, Math.round(v))); })()",
        )
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    let shot = tab.call(
        "Page.captureScreenshot",
        &json!({"format": "png", "fromSurface": true}),
    );
    let shot = base64::Engine::decode(
        &base64::engine::general_purpose::STANDARD,
        shot["data"].as_str().unwrap(),
    )
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
    std::fs::write(&shot_path, &shot).unwrap();
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

    // Events still queued arrive with this last reply.
    tab.eval("0");
    let mut errors = Vec::new();
    let mut requests = Vec::new();
    for event in &tab.events {
        let p = &event["params"];
        match event["method"].as_str().unwrap_or_default() {
            "Runtime.consoleAPICalled"
                if matches!(p["type"].as_str(), Some("error" | "assert")) =>
            {
                let text: Vec<String> = p["args"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|a| match (&a["value"], &a["description"]) {
                        (Value::Null, Value::String(d)) => d.clone(),
                        (v, _) => v.to_string(),
                    })
                    .collect();
                errors.push(format!("console.error: {}", text.join(" ")));
            }
            "Runtime.exceptionThrown" => {
                let d = &p["exceptionDetails"];
                errors.push(format!(
                    "exception: {} {}",
                    d["text"], d["exception"]["description"]
                ));
            }
            "Log.entryAdded" if p["entry"]["level"] == "error" => {
                errors.push(format!("log: {}", p["entry"]["text"]));
            }
            "Network.requestWillBeSent" => {
                requests.push(p["request"]["url"].as_str().unwrap_or_default().to_owned());
            }
            _ => {}
        }
    }
    assert!(errors.is_empty(), "console errors: {errors:#?}");
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

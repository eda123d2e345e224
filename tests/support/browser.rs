//! Headless Chromium driven through chromedriver (WebDriver), for the viewer's browser tests
//! and its benchmark. Each [`Browser`] starts its own chromedriver on a free loopback port,
//! in its own process group, and ends that group when dropped.
//!
//! The browser runs with its proxy set to a closed loopback port: a request to any host other
//! than the loopback one (which Chromium never sends through a proxy) fails, so a page that
//! needs the network shows it.
#![allow(dead_code)]

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use fantoccini::wd::Capabilities;
use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{Value, json};

/// Where chromedriver is: `$CHROMEDRIVER` (when set, nothing else is tried), else the first
/// `chromedriver` on `$PATH`, else the Debian package's path.
pub fn chromedriver_path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CHROMEDRIVER") {
        let p = PathBuf::from(p);
        return p.is_file().then_some(p);
    }
    let on_path = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("chromedriver"))
            .find(|p| p.is_file())
    });
    on_path.or_else(|| {
        let p = Path::new("/usr/bin/chromedriver");
        p.is_file().then(|| p.to_path_buf())
    })
}

/// A headless Chromium session.
pub struct Browser {
    /// The WebDriver session.
    pub client: Client,
    driver: Child,
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("no free loopback port")
}

impl Browser {
    /// Starts chromedriver and a headless Chromium with a `width` × `height` window.
    ///
    /// Panics with the way to install them when chromedriver is missing: the browser tests
    /// never skip silently.
    pub async fn start(width: u32, height: u32) -> Browser {
        let Some(exe) = chromedriver_path() else {
            panic!(
                "chromedriver not found ($CHROMEDRIVER, $PATH, /usr/bin/chromedriver): the \
                 browser tests need headless Chromium — install the Debian packages \
                 `chromium` and `chromium-driver` (`apt-get install -y chromium \
                 chromium-driver`; .ci/run does this)"
            );
        };
        let port = free_port();
        let mut cmd = Command::new(&exe);
        cmd.arg(format!("--port={port}"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        #[cfg(unix)]
        std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
        let mut driver = cmd
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {}: {e}", exe.display()));
        let url = format!("http://127.0.0.1:{port}");
        let mut args = vec![
            "--headless=new".to_string(),
            "--no-sandbox".into(),
            "--disable-gpu".into(),
            "--disable-dev-shm-usage".into(),
            "--disable-extensions".into(),
            "--disable-background-networking".into(),
            "--disable-component-update".into(),
            "--disable-sync".into(),
            "--no-first-run".into(),
            "--hide-scrollbars".into(),
            format!("--window-size={width},{height}"),
            // Nothing listens on port 9 (discard): every non-loopback request fails.
            "--proxy-server=http://127.0.0.1:9".into(),
        ];
        if let Some(extra) = std::env::var_os("GSPN_CHROME_ARGS") {
            args.extend(extra.to_string_lossy().split_whitespace().map(String::from));
        }
        let mut options = json!({ "args": args });
        if let Some(bin) = std::env::var_os("CHROME_BIN") {
            options["binary"] = json!(bin.to_string_lossy());
        }
        let mut caps = Capabilities::new();
        caps.insert("browserName".into(), json!("chrome"));
        caps.insert("goog:chromeOptions".into(), options);
        let connector = hyper_util::client::legacy::connect::HttpConnector::new();
        let mut last = String::new();
        for _ in 0..200 {
            match ClientBuilder::new(connector.clone())
                .capabilities(caps.clone())
                .connect(&url)
                .await
            {
                Ok(client) => return Browser { client, driver },
                Err(e) => last = e.to_string(),
            }
            if let Ok(Some(status)) = driver.try_wait() {
                panic!("chromedriver exited ({status}) before accepting a session: {last}");
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
        let _ = driver.kill();
        panic!("no WebDriver session from chromedriver at {url}: {last}");
    }

    /// Runs `script` (a function body; `arguments[i]` are `args`) and returns its value.
    pub async fn js(&self, script: &str, args: Vec<Value>) -> Value {
        self.client
            .execute(script, args)
            .await
            .unwrap_or_else(|e| panic!("script failed: {e}\n{script}"))
    }

    /// Polls `script` every 20 ms until it returns something truthy (not `null`, `false`,
    /// `0`, `""`); returns that. Panics after `timeout` with `what`.
    pub async fn wait_js(&self, script: &str, timeout: Duration, what: &str) -> Value {
        let start = std::time::Instant::now();
        loop {
            let v = self.js(script, vec![]).await;
            let truthy = match &v {
                Value::Null | Value::Bool(false) => false,
                Value::Number(n) => n.as_f64() != Some(0.0),
                Value::String(s) => !s.is_empty(),
                _ => true,
            };
            if truthy {
                return v;
            }
            if start.elapsed() > timeout {
                let status = self.text("#status").await;
                panic!("timed out waiting for {what} (page status: {status:?})");
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    /// Clicks the element matching `css`.
    pub async fn click(&self, css: &str) {
        self.client
            .find(Locator::Css(css))
            .await
            .unwrap_or_else(|e| panic!("no element {css}: {e}"))
            .click()
            .await
            .unwrap_or_else(|e| panic!("cannot click {css}: {e}"));
    }

    /// The text of the element matching `css` (empty when there is none).
    pub async fn text(&self, css: &str) -> String {
        self.js(
            "const e = document.querySelector(arguments[0]); return e ? e.textContent : '';",
            vec![json!(css)],
        )
        .await
        .as_str()
        .unwrap_or_default()
        .to_string()
    }

    /// Saves a PNG screenshot of the window as `path` (directories created).
    pub async fn screenshot(&self, path: &Path) {
        let png = self.client.screenshot().await.expect("screenshot");
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).expect("screenshot directory");
        }
        std::fs::write(path, png).expect("write screenshot");
    }

    /// Ends the session and chromedriver.
    pub async fn close(mut self) {
        let _ = self.client.clone().close().await;
        self.kill_driver();
    }

    fn kill_driver(&mut self) {
        #[cfg(unix)]
        // SAFETY: `kill` on the process group this Browser created (chromedriver and the
        // Chromium it started); no memory is involved.
        unsafe {
            libc::kill(-(self.driver.id() as i32), libc::SIGKILL);
        }
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        if let Ok(None) = self.driver.try_wait() {
            self.kill_driver();
        }
    }
}

/// The viewer's live frames over some seconds of real time, as the page times them
/// (`window.gspnPerf`, see `assets/live.js`), in milliseconds.
#[derive(Debug)]
pub struct LiveFrames {
    /// WebSocket message → the paint after it, per frame.
    pub paint: Vec<f64>,
    /// The page's own script, per frame.
    pub script: Vec<f64>,
    /// The page's clock at the end (model time, firings).
    pub clock: String,
}

impl Browser {
    /// Clears the page's frame timings, waits `seconds` (real time) and reads them.
    pub async fn live_frames(&self, seconds: u64) -> LiveFrames {
        self.js(
            "window.gspnPerf.frames = []; window.gspnPerf.handler = [];",
            vec![],
        )
        .await;
        tokio::time::sleep(Duration::from_secs(seconds)).await;
        let perf = self
            .js(
                "return {frames: window.gspnPerf.frames, handler: window.gspnPerf.handler, \
                 clock: document.getElementById('clock').textContent};",
                vec![],
            )
            .await;
        let list = |v: &Value| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().filter_map(Value::as_f64).collect())
                .unwrap_or_default()
        };
        LiveFrames {
            paint: list(&perf["frames"]),
            script: list(&perf["handler"]),
            clock: perf["clock"].as_str().unwrap_or("").to_string(),
        }
    }
}

impl LiveFrames {
    /// `N frames in S s; message → paint median …, p90 …, max …; script per frame median …`.
    pub fn summary(&self, seconds: u64) -> String {
        format!(
            "{} frames in {seconds} s; message → paint median {:.1} ms, p90 {:.1} ms, max {:.1} \
             ms; script per frame median {:.1} ms ({})",
            self.paint.len(),
            quantile(&self.paint, 0.5),
            quantile(&self.paint, 0.9),
            self.paint.iter().copied().fold(0.0, f64::max),
            quantile(&self.script, 0.5),
            self.clock,
        )
    }
}

/// The `q` quantile of `v` (the element at rank round((n − 1)·q)); NaN when empty.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[((v.len() - 1) as f64 * q).round() as usize]
}

//! A minimal Chrome DevTools Protocol client for tests: starts headless Chromium as a child
//! process, talks to it over a plain WebSocket on localhost (`tungstenite`), and drives one
//! page the way a user would (real key and mouse events through `Input.*`).
//!
//! Every wait is bounded: a browser that hangs or dies fails the test with a message (and the
//! tail of Chromium's stderr), never hangs it. The bound is a number of idle waits of
//! [`SLICE`] each ([`Patience`]), not a clock read, so no test here reads the time. Dropping [`Chromium`] closes the
//! browser, kills it if it does not exit, and removes its temporary profile.
//!
//! Protocol errors, timeouts and JavaScript exceptions panic with a message, as an assertion
//! would; only [`Chromium::launch`] returns an error, for the caller to tell "no browser
//! installed" (skip) from "the browser is broken" (fail).

use serde_json::{Value, json};
use std::io::{BufRead, BufReader, ErrorKind};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tungstenite::{Message, WebSocket};

/// The executable used when `RAYBENCH_CHROMIUM` is not set: Debian's `chromium` package.
const DEFAULT_CHROMIUM: &str = "/usr/bin/chromium";

/// How long Chromium may take to start and print its DevTools address (a cold start on a
/// loaded two-core machine takes a few seconds).
const START_TIMEOUT: Duration = Duration::from_secs(60);

/// How long one command or one awaited event may take.
const TIMEOUT: Duration = Duration::from_secs(30);

/// How long a closing browser gets before it is killed.
const CLOSE_TIMEOUT: Duration = Duration::from_secs(5);

/// One idle wait: a read that times out, a poll's pause.
const SLICE: Duration = Duration::from_millis(20);

/// A bounded wait counted in idle [`SLICE`]s instead of read from a clock: a wait of `limit`
/// gives up after `limit / SLICE` slices in which nothing happened (time spent handling
/// messages is not counted, so the bound is a little longer than `limit` in wall time).
struct Patience {
    /// Idle slices left.
    slices: u128,
}

impl Patience {
    /// Patience for about `limit` of idle time.
    fn new(limit: Duration) -> Self {
        Self {
            slices: limit.as_millis() / SLICE.as_millis(),
        }
    }

    /// Spends one idle slice; false when none was left.
    fn spend(&mut self) -> bool {
        let left = self.slices > 0;
        self.slices = self.slices.saturating_sub(1);
        left
    }
}

/// How many lines of Chromium's stderr a failure message quotes.
const STDERR_TAIL: usize = 20;

/// The viewport of every page, in CSS pixels (also the window size on the command line).
const VIEWPORT: (u32, u32) = (1400, 1000);

/// Why no browser could be started.
#[derive(Debug)]
pub enum LaunchError {
    /// No Chromium executable at the path: the caller may skip.
    Absent(String),
    /// Chromium is there but did not start or did not answer: the caller should fail.
    Broken(String),
}

/// A running headless Chromium and the WebSocket connection to its browser target.
pub struct Chromium {
    child: Child,
    profile: PathBuf,
    ws: WebSocket<TcpStream>,
    stderr: Arc<Mutex<Vec<String>>>,
    next_id: u64,
    /// Every event received, in order (`method`, `params`, and `sessionId` for a page's).
    events: Vec<Value>,
}

impl Chromium {
    /// Starts Chromium (`RAYBENCH_CHROMIUM`, else `/usr/bin/chromium`) headless with a fresh
    /// profile and connects to it.
    ///
    /// # Errors
    /// [`LaunchError::Absent`] when the executable does not exist, [`LaunchError::Broken`]
    /// when it cannot be started, exits, or does not print its DevTools address in time.
    pub fn launch() -> Result<Chromium, LaunchError> {
        let exe = std::env::var_os("RAYBENCH_CHROMIUM")
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from(DEFAULT_CHROMIUM));
        if !exe.is_file() {
            let how = if std::env::var_os("RAYBENCH_CHROMIUM").is_some() {
                "RAYBENCH_CHROMIUM names"
            } else {
                "no RAYBENCH_CHROMIUM, and Debian's package `chromium` provides"
            };
            return Err(LaunchError::Absent(format!(
                "{} does not exist ({how} it)",
                exe.display()
            )));
        }
        let profile = fresh_profile_dir();
        let spawned = Command::new(&exe)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                // CI's closed network refuses Chromium's background connections (many at a
                // time, and a failed look-up of Google's hosts at every start); these flags
                // keep it from trying.
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--disable-dev-shm-usage",
                "--remote-debugging-port=0",
            ])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(format!("--window-size={},{}", VIEWPORT.0, VIEWPORT.1))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn();
        let mut child = match spawned {
            Ok(child) => child,
            Err(e) => {
                let _ = std::fs::remove_dir_all(&profile);
                return Err(LaunchError::Broken(format!(
                    "cannot start {}: {e}",
                    exe.display()
                )));
            }
        };
        // A thread reads stderr for the whole life of the browser (a full pipe would block
        // it), keeps the lines for failure messages, and hands them over until the address.
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let (tx, rx) = mpsc::channel();
        let pipe = child.stderr.take().expect("stderr is piped");
        let lines = Arc::clone(&stderr);
        std::thread::spawn(move || {
            for line in BufReader::new(pipe).lines() {
                let Ok(line) = line else { break };
                // Without a D-Bus (containers, CI) Chromium complains at every start; those
                // lines would hide the ones that explain a failure.
                if !line.contains(":ERROR:dbus/") {
                    lines.lock().unwrap().push(line.clone());
                }
                let _ = tx.send(line);
            }
        });
        let address = match wait_for_address(&rx, &mut child) {
            Ok(address) => address,
            Err(why) => {
                let _ = child.kill();
                let _ = child.wait();
                let _ = std::fs::remove_dir_all(&profile);
                return Err(LaunchError::Broken(format!(
                    "{} {why}; its stderr:\n{}",
                    exe.display(),
                    tail(&stderr)
                )));
            }
        };
        let ws = match connect(&address) {
            Ok(ws) => ws,
            Err(why) => {
                let _ = child.kill();
                let _ = child.wait();
                let _ = std::fs::remove_dir_all(&profile);
                return Err(LaunchError::Broken(format!("{address}: {why}")));
            }
        };
        Ok(Chromium {
            child,
            profile,
            ws,
            stderr,
            next_id: 1,
            events: Vec::new(),
        })
    }

    /// Opens a new page (tab) at `about:blank`, attached as a flat session with the
    /// `Runtime`, `Log` and `Page` domains enabled, so its errors are recorded from the start.
    pub fn new_page(&mut self) -> Page<'_> {
        let target = self.call(None, "Target.createTarget", json!({"url": "about:blank"}));
        let target_id = target["targetId"]
            .as_str()
            .expect("a target id")
            .to_string();
        let attached = self.call(
            None,
            "Target.attachToTarget",
            json!({"targetId": target_id, "flatten": true}),
        );
        let session = attached["sessionId"]
            .as_str()
            .expect("a session id")
            .to_string();
        let first_event = self.events.len();
        let mut page = Page {
            browser: self,
            session,
            first_event,
        };
        for domain in ["Runtime", "Log", "Page"] {
            page.call(&format!("{domain}.enable"), json!({}));
        }
        page.call(
            "Emulation.setDeviceMetricsOverride",
            json!({"width": VIEWPORT.0, "height": VIEWPORT.1, "deviceScaleFactor": 1, "mobile": false}),
        );
        page
    }

    /// Sends one command (to a page when `session` is given) and returns its result,
    /// keeping every event that arrives meanwhile.
    ///
    /// # Panics
    /// When the browser answers with an error, the connection fails, or no answer comes
    /// within [`TIMEOUT`].
    fn call(&mut self, session: Option<&str>, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        let mut message = json!({"id": id, "method": method, "params": params});
        if let Some(session) = session {
            message["sessionId"] = json!(session);
        }
        if let Err(e) = self.ws.send(Message::text(message.to_string())) {
            self.fail(&format!("cannot send {method}: {e}"));
        }
        let mut patience = Patience::new(TIMEOUT);
        loop {
            let reply = match self.receive(&mut patience) {
                Some(Incoming::Reply(reply)) => reply,
                Some(Incoming::Event) => continue,
                None => self.fail(&format!("no answer to {method} within {TIMEOUT:?}")),
            };
            if reply.get("id").and_then(Value::as_u64) == Some(id) {
                if let Some(error) = reply.get("error") {
                    self.fail(&format!(
                        "{method} {params}: {error}",
                        params = message["params"]
                    ));
                }
                return reply["result"].clone();
            }
        }
    }

    /// Reads the next message: an event is recorded, a command's reply returned. `None` when
    /// `patience` runs out first (each read that times out spends a slice).
    fn receive(&mut self, patience: &mut Patience) -> Option<Incoming> {
        loop {
            // Reads time out after one slice; tungstenite keeps a partly read frame across
            // `WouldBlock`.
            if let Err(e) = self.ws.get_ref().set_read_timeout(Some(SLICE)) {
                self.fail(&format!("cannot set a read timeout: {e}"));
            }
            match self.ws.read() {
                Ok(Message::Text(text)) => {
                    let value: Value = match serde_json::from_str(text.as_str()) {
                        Ok(value) => value,
                        Err(e) => self.fail(&format!("a message that is not JSON ({e}): {text}")),
                    };
                    if value.get("id").is_some() {
                        return Some(Incoming::Reply(value));
                    }
                    self.events.push(value);
                    return Some(Incoming::Event);
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                {
                    if !patience.spend() {
                        return None;
                    }
                }
                Err(e) => self.fail(&format!("the DevTools connection failed: {e}")),
            }
        }
    }

    /// Panics with `why` and the tail of Chromium's stderr.
    fn fail(&mut self, why: &str) -> ! {
        let status = match self.child.try_wait() {
            Ok(Some(status)) => format!("Chromium exited ({status})"),
            _ => "Chromium is running".to_string(),
        };
        panic!(
            "DevTools: {why}\n{status}; the last lines of its stderr:\n{}",
            tail(&self.stderr)
        );
    }
}

impl Drop for Chromium {
    fn drop(&mut self) {
        // Ask politely (Chromium then ends its renderer and GPU processes too), kill if it
        // does not exit in time.
        let id = self.next_id;
        let _ = self.ws.send(Message::text(
            json!({"id": id, "method": "Browser.close", "params": {}}).to_string(),
        ));
        let mut patience = Patience::new(CLOSE_TIMEOUT);
        loop {
            match self.child.try_wait() {
                Ok(Some(_)) => break,
                Ok(None) if patience.spend() => std::thread::sleep(SLICE),
                _ => {
                    let _ = self.child.kill();
                    let _ = self.child.wait();
                    break;
                }
            }
        }
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

/// A message from the browser.
enum Incoming {
    /// The reply to a command (`id`, and `result` or `error`).
    Reply(Value),
    /// An event, now at the end of [`Chromium::events`].
    Event,
}

/// One page of the browser, driven through its flat session.
pub struct Page<'a> {
    browser: &'a mut Chromium,
    session: String,
    /// The index of the first event that may belong to this page.
    first_event: usize,
}

impl Page<'_> {
    /// Sends one command to this page and returns its result.
    ///
    /// # Panics
    /// As [`Chromium::call`].
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        let session = self.session.clone();
        self.browser.call(Some(&session), method, params)
    }

    /// Navigates to `url` and waits for its load event.
    ///
    /// # Panics
    /// When navigation fails or the page does not load within [`TIMEOUT`].
    pub fn navigate(&mut self, url: &str) {
        let from = self.browser.events.len();
        let result = self.call("Page.navigate", json!({ "url": url }));
        if let Some(error) = result.get("errorText").and_then(Value::as_str) {
            self.browser.fail(&format!("cannot load {url}: {error}"));
        }
        self.wait_event(
            from,
            "Page.loadEventFired",
            &format!("the load event of {url}"),
        );
    }

    /// Waits until this page sends event `method` (looking at events from index `from`).
    fn wait_event(&mut self, from: usize, method: &str, what: &str) {
        let mut patience = Patience::new(TIMEOUT);
        let mut seen = from;
        loop {
            let events = &self.browser.events;
            if events[seen..]
                .iter()
                .any(|e| e["method"] == method && e["sessionId"] == self.session.as_str())
            {
                return;
            }
            seen = events.len();
            // A command reply cannot arrive here: every command waits for its own.
            if self.browser.receive(&mut patience).is_none() {
                self.browser.fail(&format!("no {what} within {TIMEOUT:?}"));
            }
        }
    }

    /// Evaluates a JavaScript expression in the page and returns its value (as JSON;
    /// promises are awaited).
    ///
    /// # Panics
    /// When the expression throws.
    pub fn eval(&mut self, expression: &str) -> Value {
        let reply = self.call(
            "Runtime.evaluate",
            json!({"expression": expression, "returnByValue": true, "awaitPromise": true}),
        );
        if let Some(details) = reply.get("exceptionDetails") {
            let what = details["exception"]["description"]
                .as_str()
                .or(details["text"].as_str())
                .unwrap_or("an exception");
            panic!("JavaScript `{expression}` threw: {what}");
        }
        reply["result"]["value"].clone()
    }

    /// Every error the page reported since it was opened: uncaught exceptions,
    /// `console.error` and failed `console.assert` calls, and error-level log entries (a
    /// resource that failed to load, a blocked request), one line each.
    pub fn errors(&mut self) -> Vec<String> {
        // A round trip: the events the page sent before it arrive before its reply.
        self.eval("0");
        self.browser.events[self.first_event..]
            .iter()
            .filter(|e| e["sessionId"] == self.session.as_str())
            .filter_map(describe_error)
            .collect()
    }

    /// Presses and releases one key (`ArrowRight`, `ArrowLeft`, a digit, a lower-case
    /// letter, `+` or `-`) on whatever element has focus.
    ///
    /// # Panics
    /// For a key this table does not know.
    pub fn press(&mut self, key: &str) {
        let (code, vk, shift) = match key {
            "ArrowLeft" => ("ArrowLeft".to_string(), 37, false),
            "ArrowRight" => ("ArrowRight".to_string(), 39, false),
            "+" => ("Equal".to_string(), 187, true),
            "-" => ("Minus".to_string(), 189, false),
            _ => match key.as_bytes() {
                [c @ b'0'..=b'9'] => (format!("Digit{}", *c as char), u32::from(*c), false),
                [c @ b'a'..=b'z'] => (
                    format!("Key{}", c.to_ascii_uppercase() as char),
                    u32::from(c.to_ascii_uppercase()),
                    false,
                ),
                _ => panic!("no key code for {key:?}"),
            },
        };
        let printable = key.chars().count() == 1;
        let modifiers = if shift { 8 } else { 0 };
        let mut down = json!({
            "type": if printable { "keyDown" } else { "rawKeyDown" },
            "key": key,
            "code": code,
            "windowsVirtualKeyCode": vk,
            "nativeVirtualKeyCode": vk,
            "modifiers": modifiers,
        });
        if printable {
            down["text"] = json!(key);
            down["unmodifiedText"] = json!(key);
        }
        self.call("Input.dispatchKeyEvent", down);
        self.call(
            "Input.dispatchKeyEvent",
            json!({
                "type": "keyUp",
                "key": key,
                "code": code,
                "windowsVirtualKeyCode": vk,
                "nativeVirtualKeyCode": vk,
                "modifiers": modifiers,
            }),
        );
    }

    /// Scrolls the first element matching CSS `selector` into view and clicks its centre
    /// with the left mouse button (move, press, release).
    ///
    /// # Panics
    /// When nothing matches or the element has no area.
    pub fn click(&mut self, selector: &str) {
        self.click_element(&query(selector), selector);
    }

    /// Clicks the element that the JavaScript expression `element` yields, as [`Page::click`]
    /// does; `what` names it in failure messages.
    pub fn click_element(&mut self, element: &str, what: &str) {
        let r = self.rect(element, what);
        let (x, y) = (r[0] + r[2] / 2.0, r[1] + r[3] / 2.0);
        for (kind, buttons) in [("mouseMoved", 0), ("mousePressed", 1), ("mouseReleased", 0)] {
            let mut event = json!({"type": kind, "x": x, "y": y, "buttons": buttons});
            if kind != "mouseMoved" {
                event["button"] = json!("left");
                event["clickCount"] = json!(1);
            }
            self.call("Input.dispatchMouseEvent", event);
        }
    }

    /// The box `[x, y, width, height]` in the viewport (CSS pixels) of the element that the
    /// JavaScript expression `element` yields, after scrolling it into the middle of the view.
    fn rect(&mut self, element: &str, what: &str) -> [f64; 4] {
        let r = self.eval(&format!(
            "(() => {{ const e = {element}; if (!e) return null; \
             e.scrollIntoView({{block: 'center', inline: 'center'}}); \
             const r = e.getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; }})()"
        ));
        let Some(r) = r.as_array().filter(|r| r.len() == 4) else {
            panic!("no element {what} on the page");
        };
        let r: Vec<f64> = r.iter().map(|v| v.as_f64().unwrap_or(0.0)).collect();
        assert!(
            r[2] > 0.0 && r[3] > 0.0,
            "{what} has no area on the page: {r:?}"
        );
        [r[0], r[1], r[2], r[3]]
    }

    /// Waits until the JavaScript expression `condition` is true (polling every [`SLICE`]), for
    /// what a page does after an event (an image loading).
    ///
    /// # Panics
    /// When it is still false after [`TIMEOUT`]; the message names `what`.
    pub fn wait_until(&mut self, condition: &str, what: &str) {
        let mut patience = Patience::new(TIMEOUT);
        while self.eval(condition) != json!(true) {
            if !patience.spend() {
                panic!("not {what} after {TIMEOUT:?} (`{condition}` is still false)");
            }
            std::thread::sleep(SLICE);
        }
    }

    /// A PNG of the element matching `selector` as shown on screen (after scrolling it
    /// into view).
    pub fn screenshot(&mut self, selector: &str) -> Vec<u8> {
        use base64::Engine as _;
        let r = self.rect(&query(selector), selector);
        // The clip is in document coordinates.
        let scroll = self.eval("[window.scrollX, window.scrollY]");
        let (sx, sy) = (
            scroll[0].as_f64().unwrap_or(0.0),
            scroll[1].as_f64().unwrap_or(0.0),
        );
        let shot = self.call(
            "Page.captureScreenshot",
            json!({"format": "png", "clip": {
                "x": r[0] + sx, "y": r[1] + sy, "width": r[2], "height": r[3], "scale": 1
            }}),
        );
        let data = shot["data"].as_str().expect("screenshot data");
        base64::engine::general_purpose::STANDARD
            .decode(data)
            .expect("the screenshot is base64")
    }
}

/// One line for an event that reports an error, `None` for any other event.
fn describe_error(event: &Value) -> Option<String> {
    let p = &event["params"];
    match event["method"].as_str()? {
        "Runtime.exceptionThrown" => {
            let d = &p["exceptionDetails"];
            let what = d["exception"]["description"]
                .as_str()
                .or(d["text"].as_str())
                .unwrap_or("?");
            // Line numbers are counted from 0.
            let line = d["lineNumber"].as_u64().map_or(0, |n| n + 1);
            Some(format!(
                "uncaught exception at {}:{line}: {what}",
                d["url"].as_str().unwrap_or("?"),
            ))
        }
        "Runtime.consoleAPICalled" if matches!(p["type"].as_str(), Some("error" | "assert")) => {
            let args: Vec<String> = p["args"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|a| match &a["value"] {
                    Value::Null => a["description"].as_str().unwrap_or("?").to_string(),
                    Value::String(s) => s.clone(),
                    v => v.to_string(),
                })
                .collect();
            Some(format!(
                "console.{}: {}",
                p["type"].as_str()?,
                args.join(" ")
            ))
        }
        "Log.entryAdded" if p["entry"]["level"] == "error" => {
            let e = &p["entry"];
            Some(format!(
                "{} error: {} ({})",
                e["source"].as_str().unwrap_or("?"),
                e["text"].as_str().unwrap_or("?"),
                e["url"].as_str().unwrap_or("no url")
            ))
        }
        _ => None,
    }
}

/// The JavaScript expression for the first element matching CSS `selector`.
fn query(selector: &str) -> String {
    format!("document.querySelector({})", json!(selector))
}

/// Waits for the line `DevTools listening on ws://...` and returns the address.
fn wait_for_address(rx: &mpsc::Receiver<String>, child: &mut Child) -> Result<String, String> {
    let mut patience = Patience::new(START_TIMEOUT);
    loop {
        match rx.recv_timeout(SLICE) {
            Ok(line) => {
                if let Some(address) = line.strip_prefix("DevTools listening on ") {
                    return Ok(address.trim().to_string());
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) if patience.spend() => {}
            Err(mpsc::RecvTimeoutError::Timeout) => {
                return Err(format!(
                    "printed no DevTools address within {START_TIMEOUT:?}"
                ));
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let status = child
                    .wait()
                    .map_or_else(|e| e.to_string(), |s| s.to_string());
                return Err(format!(
                    "closed its stderr without a DevTools address ({status})"
                ));
            }
        }
    }
}

/// Opens the WebSocket to `ws://127.0.0.1:PORT/devtools/browser/ID`.
fn connect(address: &str) -> Result<WebSocket<TcpStream>, String> {
    let host = address
        .strip_prefix("ws://")
        .and_then(|rest| rest.split('/').next())
        .ok_or_else(|| format!("not a ws:// address: {address}"))?;
    let stream = TcpStream::connect(host).map_err(|e| format!("cannot connect: {e}"))?;
    stream
        .set_read_timeout(Some(TIMEOUT))
        .and_then(|()| stream.set_write_timeout(Some(TIMEOUT)))
        .map_err(|e| format!("cannot set timeouts: {e}"))?;
    let (ws, _response) =
        tungstenite::client(address, stream).map_err(|e| format!("handshake failed: {e}"))?;
    Ok(ws)
}

/// A new, empty profile directory for one browser (under the test's temporary directory
/// in `target/`).
fn fresh_profile_dir() -> PathBuf {
    static BROWSERS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = BROWSERS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("chromium-profile-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The last lines Chromium wrote to stderr.
fn tail(stderr: &Mutex<Vec<String>>) -> String {
    let lines = stderr.lock().unwrap();
    let from = lines.len().saturating_sub(STDERR_TAIL);
    lines[from..].join("\n")
}

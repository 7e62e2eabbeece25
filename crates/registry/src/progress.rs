//! Progress on stderr for work that takes a while, shared by `render`, `compare` and
//! `report`: a live line (a bar, the steps done, the time elapsed and left, what runs now)
//! redrawn in place once a step has run for [`DELAY`], on a terminal only, so that logs and
//! pipes stay clean. `RAYBENCH_PROGRESS` overrides the choice: `never`, or `always` (the
//! line at once and on any stderr, one line per redraw).

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a step runs before the live line appears.
pub const DELAY: Duration = Duration::from_secs(2);

/// How often the live line is redrawn.
const TICK: Duration = Duration::from_millis(250);

/// When the live line is shown, and whether the report's step records are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Display {
    /// Nothing: no live line and no step records (`RAYBENCH_PROGRESS=never`).
    Never,
    /// No live line (stderr is not a terminal); [`Progress::step`]'s records are printed as
    /// plain lines without the bar, for the log.
    Log,
    /// On a terminal, redrawn in place once a step has run for [`DELAY`].
    Terminal,
    /// At the start of every step and at every tick, one line each, on any stderr
    /// (`RAYBENCH_PROGRESS=always`).
    Always,
}

impl Display {
    /// The choice for this process: `RAYBENCH_PROGRESS` (`never`, `always`; any other value
    /// is ignored with one warning), else [`Display::Terminal`] when stderr is a terminal,
    /// else [`Display::Log`].
    #[must_use]
    pub fn from_env() -> Self {
        let var = std::env::var("RAYBENCH_PROGRESS");
        match var.as_deref() {
            Ok("never") => return Self::Never,
            Ok("always") => return Self::Always,
            Ok(other) => {
                static WARNED: std::sync::Once = std::sync::Once::new();
                WARNED.call_once(|| {
                    eprintln!(
                        "warning: RAYBENCH_PROGRESS='{other}' is ignored (it takes never or always)"
                    );
                });
            }
            Err(_) => {}
        }
        if std::io::stderr().is_terminal() {
            Self::Terminal
        } else {
            Self::Log
        }
    }

    /// Whether it draws a live line (and so needs the ticker).
    fn live(self) -> bool {
        matches!(self, Self::Terminal | Self::Always)
    }
}

/// The state the ticker thread reads.
struct State {
    total: usize,
    done: usize,
    start: Instant,
    /// What runs now, and since when (`None` between steps).
    current: Option<(String, Instant)>,
    /// Whether a live line is on the terminal (to be cleared before other output).
    drawn: bool,
}

impl State {
    /// The live line now, or `None` while no step has run for `delay`.
    fn line(&self, now: Instant, delay: Duration) -> Option<String> {
        let current = self
            .current
            .as_ref()
            .map(|(what, since)| (what.as_str(), now.duration_since(*since)));
        live_line(
            self.done,
            self.total,
            now.duration_since(self.start),
            current,
            delay,
        )
    }
}

/// The live line after `elapsed`, with `done` of `total` steps done and `current` (what
/// runs now, and for how long) running: `None` between steps and while the step has run for
/// less than `delay` (short steps show nothing), else [`status_line`].
#[must_use]
pub fn live_line(
    done: usize,
    total: usize,
    elapsed: Duration,
    current: Option<(&str, Duration)>,
    delay: Duration,
) -> Option<String> {
    let (what, step) = current?;
    (step >= delay).then(|| status_line(done, total, elapsed.as_secs_f64(), what))
}

/// `[######..................] 3/12  0m41s elapsed, ~2m03s left  what`; the time left is
/// extrapolated from the steps done (omitted before the first).
#[must_use]
pub fn status_line(done: usize, total: usize, elapsed: f64, what: &str) -> String {
    const WIDTH: usize = 24;
    let filled = (done * WIDTH / total.max(1)).min(WIDTH);
    let left = if done == 0 {
        String::new()
    } else {
        let left = elapsed / done as f64 * total.saturating_sub(done) as f64;
        format!(", ~{} left", clock(left))
    };
    format!(
        "[{}{}] {done}/{total}  {} elapsed{left}  {what}",
        "#".repeat(filled),
        ".".repeat(WIDTH - filled),
        clock(elapsed),
    )
}

/// A step's record in a log: `3/12  0m41s  what` (the status line without its bar and
/// estimate).
#[must_use]
pub fn record_line(done: usize, total: usize, elapsed: f64, what: &str) -> String {
    format!("{done}/{total}  {}  {what}", clock(elapsed))
}

/// `2m05s`.
#[must_use]
pub fn clock(seconds: f64) -> String {
    let s = seconds.max(0.0).round() as u64;
    format!("{}m{:02}s", s / 60, s % 60)
}

/// Progress through `total` steps. Dropping it stops the ticker and clears the live line.
pub struct Progress {
    state: Arc<Mutex<State>>,
    display: Display,
    stop: Arc<AtomicBool>,
    ticker: Option<JoinHandle<()>>,
}

impl Progress {
    /// Progress through `total` steps, shown as [`Display::from_env`] says.
    #[must_use]
    pub fn new(total: usize) -> Self {
        Self::with_display(total, Display::from_env())
    }

    /// Progress through `total` steps, shown as `display` says.
    #[must_use]
    pub fn with_display(total: usize, display: Display) -> Self {
        let state = Arc::new(Mutex::new(State {
            total,
            done: 0,
            start: Instant::now(),
            current: None,
            drawn: false,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let ticker = display.live().then(|| {
            let (state, stop) = (Arc::clone(&state), Arc::clone(&stop));
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    std::thread::park_timeout(TICK);
                    if !stop.load(Ordering::Relaxed) {
                        draw(&state, display);
                    }
                }
            })
        });
        Self {
            state,
            display,
            stop,
            ticker,
        }
    }

    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Says what runs from now on (until the next call, [`Self::done`] or [`Self::step`]).
    pub fn begin(&self, what: impl Into<String>) {
        self.state().current = Some((what.into(), Instant::now()));
        if self.display == Display::Always {
            draw(&self.state, self.display);
        }
    }

    /// One step done, quietly (the caller prints its own result lines).
    pub fn done(&self) {
        let mut s = self.state();
        s.done += 1;
        s.current = None;
        clear(&mut s);
    }

    /// One step done, with a record line: the bar, the times and `what` where a live line
    /// is shown, the same without the bar in a log ([`Display::Log`]), nothing under
    /// [`Display::Never`].
    pub fn step(&self, what: &str) {
        let mut s = self.state();
        s.done += 1;
        s.current = None;
        clear(&mut s);
        let elapsed = s.start.elapsed().as_secs_f64();
        match self.display {
            Display::Never => {}
            Display::Log => eprintln!("{}", record_line(s.done, s.total, elapsed, what)),
            Display::Terminal | Display::Always => {
                eprintln!("{}", status_line(s.done, s.total, elapsed, what));
            }
        }
    }

    /// Takes `n` steps out of the total (work found unnecessary after all).
    pub fn remove(&self, n: usize) {
        let mut s = self.state();
        s.total = s.total.saturating_sub(n);
    }

    /// Prints a line of the caller's on stderr, above the live line.
    pub fn note(&self, line: &str) {
        let mut s = self.state();
        clear(&mut s);
        eprintln!("{line}");
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.ticker.take() {
            t.thread().unpark();
            let _ = t.join();
        }
        clear(&mut self.state());
    }
}

/// Draws the live line if it is due.
fn draw(state: &Mutex<State>, display: Display) {
    let mut s = state.lock().unwrap_or_else(PoisonError::into_inner);
    let delay = if display == Display::Always {
        Duration::ZERO
    } else {
        DELAY
    };
    let Some(line) = s.line(Instant::now(), delay) else {
        return;
    };
    let mut err = std::io::stderr().lock();
    let _ = if display == Display::Terminal {
        s.drawn = true;
        // Carriage return, the line, erase to the end of the line.
        write!(err, "\r{line}\x1b[K")
    } else {
        writeln!(err, "{line}")
    };
    let _ = err.flush();
}

/// Erases a live line drawn on the terminal.
fn clear(s: &mut State) {
    if s.drawn {
        s.drawn = false;
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r\x1b[K");
        let _ = err.flush();
    }
}

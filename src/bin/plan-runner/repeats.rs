//! Repeated log lines, rate-limited (issue 32, item 8: a robot flooded with 897k garbage DDS
//! datagrams stayed up, but RustDDS warned about each one and its stderr grew to 65 MB in 3
//! minutes). Each place in the code that logs (a tracing callsite) may print
//! [`SHOWN_PER_WINDOW`] lines per [`WINDOW`]; the rest are counted, and the next line from
//! it after the window says how many were held back:
//! `… (1,204 more like this in the last 10 s)`.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use tracing::callsite::Identifier;
use tracing::{Event, Metadata, Subscriber};
use tracing_subscriber::layer::{Context, Filter};

/// How long a callsite's count runs.
pub(crate) const WINDOW: Duration = Duration::from_secs(10);

/// Lines one callsite prints per [`WINDOW`] before the rest are counted instead.
pub(crate) const SHOWN_PER_WINDOW: u32 = 5;

/// One callsite's window.
#[derive(Debug, Clone, Copy)]
struct Window {
    started: Instant,
    shown: u32,
    held: u64,
}

/// What to do with a line.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Verdict {
    /// Print it; `held` lines like it were held back in the window that just ended.
    Show { held: u64 },
    /// Count it, print nothing.
    Hold,
}

/// The windows of every callsite that logged.
#[derive(Debug)]
pub(crate) struct Repeats<K> {
    windows: HashMap<K, Window>,
}

impl<K> Default for Repeats<K> {
    fn default() -> Self {
        Repeats {
            windows: HashMap::new(),
        }
    }
}

impl<K: std::hash::Hash + Eq> Repeats<K> {
    /// The verdict on a line from `key` at `now`.
    pub(crate) fn admit(&mut self, key: K, now: Instant) -> Verdict {
        let w = self.windows.entry(key).or_insert(Window {
            started: now,
            shown: 0,
            held: 0,
        });
        if now.duration_since(w.started) >= WINDOW {
            let held = w.held;
            *w = Window {
                started: now,
                shown: 1,
                held: 0,
            };
            return Verdict::Show { held };
        }
        if w.shown < SHOWN_PER_WINDOW {
            w.shown += 1;
            Verdict::Show { held: 0 }
        } else {
            w.held += 1;
            Verdict::Hold
        }
    }
}

/// A per-layer filter for the stderr log: [`Repeats`] by callsite.
#[derive(Debug, Default)]
pub(crate) struct RateLimit {
    repeats: Mutex<Repeats<Identifier>>,
}

impl<S: Subscriber> Filter<S> for RateLimit {
    fn enabled(&self, _: &Metadata<'_>, _: &Context<'_, S>) -> bool {
        true
    }

    fn callsite_enabled(&self, _: &'static Metadata<'static>) -> tracing::subscriber::Interest {
        // Asked for every event: a cached "always" would skip `event_enabled`.
        tracing::subscriber::Interest::sometimes()
    }

    fn event_enabled(&self, event: &Event<'_>, _: &Context<'_, S>) -> bool {
        let meta = event.metadata();
        let verdict = self
            .repeats
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .admit(meta.callsite(), Instant::now());
        match verdict {
            Verdict::Hold => false,
            Verdict::Show { held: 0 } => true,
            Verdict::Show { held } => {
                eprintln!(
                    "{:>5} {}: … ({} more like this in the last {} s)",
                    meta.level(),
                    meta.target(),
                    thousands(held),
                    WINDOW.as_secs()
                );
                true
            }
        }
    }
}

/// `1204` as `1,204`.
fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flood_prints_five_lines_per_window_then_the_count_of_the_rest() {
        let mut r = Repeats::default();
        let t0 = Instant::now();
        let mut shown = 0;
        for i in 0..1_209u32 {
            let at = t0 + Duration::from_millis(u64::from(i) * 5); // 200 per second
            if r.admit("dds", at) != Verdict::Hold {
                shown += 1;
            }
        }
        assert_eq!(shown, 5, "within the first 6.04 s");
        // Another callsite has its own window.
        assert_eq!(r.admit("other", t0), Verdict::Show { held: 0 });
        // The first line after the window carries the count.
        assert_eq!(r.admit("dds", t0 + WINDOW), Verdict::Show { held: 1_204 });
        assert_eq!(thousands(1_204), "1,204");
        assert_eq!(thousands(897_000), "897,000");
        assert_eq!(thousands(12), "12");
    }
}

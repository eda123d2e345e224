//! The limits on what a user may ask for, checked where input is read and enforced again
//! where a value meets a fixed-size type (docs/reliability.md lists them):
//!
//! - a token count is at most [`MAX_TOKENS`] (2³² − 1): a file asking for more is refused
//!   with its position, a firing that would go past it is refused ([`Net::fire`]);
//! - a duration is at most [`MAX_SECONDS`] (10 years): plan timeouts, time limits, the
//!   time scale, ROS 2 heartbeats, the waits in action names (`wait S`, `fire T after S`,
//!   the robot world's `measure S`) are refused above it at load, and every conversion to a
//!   [`Duration`] goes through [`duration`], which clamps instead of panicking.
//!
//! [`Net::fire`]: crate::net::Net::fire

use std::time::Duration;

pub use crate::net::{MAX_TOKENS, TOO_MANY_TOKENS};
use crate::net::{Net, Timing, TransitionId};

/// The longest duration a user may give, in seconds: 10 years of 365.25 days.
pub const MAX_SECONDS: f64 = 315_576_000.0;

/// The expectation of a duration that is out of range, for error messages.
pub const SECONDS_EXPECTED: &str =
    "must be a finite number of seconds > 0 and ≤ 315576000 (10 years)";

/// True when `secs` is a duration a user may give: finite, > 0 and ≤ [`MAX_SECONDS`].
pub fn valid_seconds(secs: f64) -> bool {
    secs.is_finite() && secs > 0.0 && secs <= MAX_SECONDS
}

/// True when `secs` is a wait a user may write in an action (`wait S`, `fire T after S`,
/// `measure S`): like [`valid_seconds`] but 0 is allowed.
pub fn valid_wait(secs: f64) -> bool {
    secs == 0.0 || valid_seconds(secs)
}

/// In real time (`scale > 0`), the first exponential transition whose mean delay
/// `scale / rate` is longer than [`MAX_SECONDS`]: a wait on the clock that would never end.
/// The plan reader, the CLI and the runtime builder all refuse a run with one.
pub fn too_slow_for_real_time(net: &Net, scale: f64) -> Option<(TransitionId, f64)> {
    if scale <= 0.0 {
        return None;
    }
    net.transition_ids()
        .find_map(|t| match net.transition(t).timing {
            Timing::Exponential { rate, .. } if scale / rate > MAX_SECONDS => Some((t, rate)),
            _ => None,
        })
}

/// `secs` as a [`Duration`], clamped to `0..=MAX_SECONDS` (NaN gives 0): where a computed
/// wait (a delay times a time scale) meets the clock, it can never panic.
///
/// ```
/// use gspn::limits::{MAX_SECONDS, duration};
/// assert_eq!(duration(1.5).as_millis(), 1500);
/// assert_eq!(duration(1e300).as_secs_f64(), MAX_SECONDS);
/// assert_eq!(duration(f64::NAN), std::time::Duration::ZERO);
/// ```
pub fn duration(secs: f64) -> Duration {
    if secs.is_nan() || secs <= 0.0 {
        return Duration::ZERO;
    }
    Duration::try_from_secs_f64(secs.min(MAX_SECONDS)).unwrap_or(Duration::ZERO)
}

//! The viewer's limits: what one request may ask for, what one connection may hold, and how
//! many connections the server keeps. Each is checked before any work starts, so a request
//! that would exceed one is refused with the limit named instead of taking the server's
//! memory or its threads (docs/viewer.md, "Limits"; issue 32 measured a 119 KiB question
//! answering 390 MB before these existed).

use std::time::Duration;

use axum::http::StatusCode;

use crate::net::Net;

/// Most time points one question (`POST /api/analysis/query`) may ask for.
pub(crate) const MAX_TIME_POINTS: usize = 1_000;

/// Most predicates one question may ask for.
pub(crate) const MAX_PREDICATES: usize = 64;

/// Longest predicate, in characters (every answer point echoes it as a key).
pub(crate) const MAX_PREDICATE_CHARS: usize = 4_096;

/// Longest place or transition name an edit may give, in characters.
pub(crate) const MAX_NAME_CHARS: usize = 256;

/// Largest answer one question may produce, in bytes of JSON (estimated before the work).
pub(crate) const MAX_ANSWER_BYTES: usize = 16 << 20;

/// Most firings one `POST /api/sim/step` may ask for.
pub(crate) const MAX_STEP: u64 = 1_000_000;

/// Firings done per hold of the token game's lock by a `step`: between two chunks other
/// requests read the state, and a step whose request went away stops.
pub(crate) const STEP_CHUNK: u64 = 10_000;

/// Longest a connection may take to send a request's headers — and so longest an idle
/// keep-alive connection is kept — before the server closes it.
pub(crate) const HEADER_TIMEOUT: Duration = Duration::from_secs(10);

/// Files the server leaves for everything but its connections (the journal, the net, the
/// runtime's own descriptors) when it sizes [`connection_cap`] by the process's file limit.
const SPARE_FILES: usize = 128;

/// Most connections the server holds at once, websockets included: the process's open-file
/// limit less [`SPARE_FILES`], at most 4,096 (at least 16). Past it a new connection is
/// answered `503` and closed at once, so a flood of idle connections cannot take the last
/// file descriptor the server needs to accept the page (they are closed after
/// [`HEADER_TIMEOUT`] anyway).
pub(crate) fn connection_cap() -> usize {
    cap_for(open_file_limit())
}

/// [`connection_cap`] under an open-file limit (1,024 when it is not known).
fn cap_for(file_limit: Option<usize>) -> usize {
    file_limit
        .unwrap_or(1_024)
        .saturating_sub(SPARE_FILES)
        .clamp(16, 4_096)
}

#[cfg(unix)]
fn open_file_limit() -> Option<usize> {
    let mut l = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit only writes the struct it is given.
    let ok = unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut l) } == 0;
    ok.then(|| usize::try_from(l.rlim_cur).unwrap_or(usize::MAX))
}

#[cfg(not(unix))]
fn open_file_limit() -> Option<usize> {
    None
}

/// Longest a websocket message may wait to be taken by a browser before the server gives
/// up on it: a client that stops reading is dropped (after a close frame saying why), not
/// buffered for.
pub(crate) const WS_SEND_TIMEOUT: Duration = Duration::from_secs(10);

/// The websocket's read and write buffers, in bytes (tungstenite's defaults are 128 KiB
/// each, most of the ~280 KB a connection held in issue 32's measurements).
pub(crate) const WS_BUFFER: usize = 8 << 10;

/// Largest message a browser may send on the live websocket (it sends none the server
/// reads; a close frame fits).
pub(crate) const WS_MAX_INCOMING: usize = 64 << 10;

/// A request refused for a limit: its status and a message naming the limit.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OverLimit {
    /// 422 for a request that asks too much, 413 for an answer that would be too large.
    pub(crate) status: StatusCode,
    /// Names the limit and the value that went past it.
    pub(crate) message: String,
}

fn too_many(message: String) -> OverLimit {
    OverLimit {
        status: StatusCode::UNPROCESSABLE_ENTITY,
        message,
    }
}

/// Checks a question of `times` and `predicates` on `net` before it is solved: the counts,
/// each predicate's length, and the size of the answer it would give
/// ([`answer_bytes`]).
pub(crate) fn check_question(
    net: &Net,
    times: &[f64],
    predicates: &[String],
) -> Result<(), OverLimit> {
    if times.len() > MAX_TIME_POINTS {
        return Err(too_many(format!(
            "transient: {} time points: at most {MAX_TIME_POINTS} per question",
            times.len()
        )));
    }
    if predicates.len() > MAX_PREDICATES {
        return Err(too_many(format!(
            "prob: {} predicates: at most {MAX_PREDICATES} per question",
            predicates.len()
        )));
    }
    if let Some((i, chars)) = predicates
        .iter()
        .map(|p| p.chars().count())
        .enumerate()
        .find(|&(_, n)| n > MAX_PREDICATE_CHARS)
    {
        return Err(too_many(format!(
            "prob #{}: {chars} characters: at most {MAX_PREDICATE_CHARS} per predicate",
            i + 1
        )));
    }
    let bytes = answer_bytes(net, times.len(), predicates);
    if bytes > MAX_ANSWER_BYTES {
        return Err(OverLimit {
            status: StatusCode::PAYLOAD_TOO_LARGE,
            message: format!(
                "the answer would be about {} MB: at most {} MB per question (ask fewer time \
                 points or predicates)",
                bytes >> 20,
                MAX_ANSWER_BYTES >> 20
            ),
        });
    }
    Ok(())
}

/// Bytes of one number with its key's quotes, colon and comma, at most (`-1.2345678901234567e-300`).
const NUMBER_BYTES: usize = 30;

/// An upper estimate of the JSON answer to `points` time points and `predicates` on `net`:
/// each point holds a number per place, per transition and per predicate, keyed by its
/// name (or text); the steady state one per predicate.
pub(crate) fn answer_bytes(net: &Net, points: usize, predicates: &[String]) -> usize {
    let keyed = |name: &str| name.len() + 2 + NUMBER_BYTES;
    let names: usize = net.places().iter().map(|p| keyed(&p.name)).sum::<usize>()
        + net
            .transitions()
            .iter()
            .map(|t| keyed(&t.name))
            .sum::<usize>();
    let probs: usize = predicates.iter().map(|p| keyed(p)).sum();
    let point = 96 + names + probs;
    points.saturating_mul(point).saturating_add(probs + 96)
}

/// Checks a name an edit gives a place or a transition: at most [`MAX_NAME_CHARS`].
pub(crate) fn name_too_long(name: &str) -> Option<usize> {
    let n = name.chars().count();
    (n > MAX_NAME_CHARS).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::NetBuilder;

    fn two_places() -> Net {
        let mut b = NetBuilder::new("n");
        let p = b.place("P", 1);
        let q = b.place("Q", 0);
        let t = b.exponential("T", 1.0, crate::net::Servers::Single);
        b.input(p, t, 1);
        b.output(t, q, 1);
        b.build().unwrap()
    }

    /// Issue 32's question: 4,000 points echoing a 99 KB predicate (≈ 390 MB answered).
    #[test]
    fn the_amplifying_question_is_refused_naming_the_limit() {
        let net = two_places();
        let times = vec![1.0; 4_000];
        let err = check_question(&net, &times, &[]).unwrap_err();
        assert_eq!(err.status, StatusCode::UNPROCESSABLE_ENTITY);
        assert_eq!(
            err.message,
            "transient: 4000 time points: at most 1000 per question"
        );
        let long = format!("#P >= 0 && {}", "#P >= 0 && ".repeat(9_000));
        let err = check_question(&net, &times[..10], std::slice::from_ref(&long)).unwrap_err();
        assert_eq!(
            err.message,
            format!(
                "prob #1: {} characters: at most 4096 per predicate",
                long.len()
            )
        );
    }

    #[test]
    fn an_answer_past_its_size_is_refused_with_413() {
        let net = two_places();
        let preds: Vec<String> = (0..64)
            .map(|i| format!("{}#P >= {i}", " ".repeat(4000)))
            .collect();
        let err = check_question(&net, &vec![1.0; 1_000], &preds).unwrap_err();
        assert_eq!(err.status, StatusCode::PAYLOAD_TOO_LARGE);
        // 1,001 × 64 predicates × ~4,040 bytes each ≈ 247 MiB.
        assert!(
            err.message.starts_with("the answer would be about 24"),
            "{}",
            err.message
        );
        assert!(err.message.contains("at most 16 MB per question"));
        assert_eq!(check_question(&net, &vec![1.0; 1_000], &preds[..1]), Ok(()));
    }

    #[test]
    fn connection_cap_leaves_room_below_the_file_limit() {
        assert_eq!(cap_for(Some(1_024)), 896);
        assert_eq!(cap_for(None), 896);
        assert_eq!(cap_for(Some(100)), 16);
        assert_eq!(cap_for(Some(1 << 20)), 4_096);
    }
}

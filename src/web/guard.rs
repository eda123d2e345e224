//! Who may talk to the viewer. A page on another site can make the browser send requests to
//! the loopback (a form post, a `fetch` in `no-cors` mode, a websocket) and a DNS-rebinding
//! page can even read the answers; so before any route runs, every request is checked:
//!
//! 1. `Host` must name this server ([`Bound`]), else **421 Misdirected Request**. A
//!    rebinding attack arrives under the attacker's domain name, which is never accepted.
//! 2. `Origin`, when present, must be this server's own origin (`http://` + the `Host`),
//!    else **403 Forbidden**. Browsers send `Origin` on every cross-origin request that can
//!    change anything and on every websocket handshake; `curl` and scripts send none.
//! 3. A request with a body-carrying method (`POST`, ...) must say
//!    `Content-Type: application/json`, else **415 Unsupported Media Type**: a cross-origin
//!    page can send a form or `text/plain` without asking, but not JSON.

use std::net::{IpAddr, SocketAddr};

use axum::extract::{Request, State};
use axum::http::header::{CONTENT_TYPE, HOST, ORIGIN};
use axum::http::uri::Authority;
use axum::http::{HeaderMap, Method, StatusCode};
use axum::middleware::Next;
use axum::response::Response;

/// Where the server listens, as far as the `Host` check is concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Bound {
    /// The router is served by someone else on an address it does not know: only the
    /// loopback names (`localhost`, `127.0.0.1`, `[::1]`) are accepted, with any port.
    Unknown,
    /// [`serve`](super::serve) on this address: its port, and as host `localhost`,
    /// `127.0.0.1`, `[::1]` or the address itself; on a non-loopback address any IP
    /// literal too (a client on the network names the machine by one of its addresses),
    /// never another domain name.
    At(SocketAddr),
}

/// Why a request was turned away: its status and message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Refusal {
    pub(crate) status: StatusCode,
    pub(crate) message: String,
}

impl Refusal {
    fn new(status: StatusCode, message: String) -> Refusal {
        Refusal { status, message }
    }
}

/// The middleware: [`check`] every request, answer a refusal as `{"error": ...}`.
pub(crate) async fn guard(State(bound): State<Bound>, req: Request, next: Next) -> Response {
    match check(bound, req.method(), req.headers()) {
        Ok(()) => next.run(req).await,
        Err(r) => super::api::error(r.status, r.message),
    }
}

/// The three checks of the [module](self), in order.
pub(crate) fn check(bound: Bound, method: &Method, headers: &HeaderMap) -> Result<(), Refusal> {
    let host = match headers.get(HOST) {
        None => None,
        Some(h) => {
            let text = h.to_str().unwrap_or("");
            match text.parse::<Authority>() {
                Ok(a) if host_allowed(bound, &a) => Some(a),
                _ => {
                    return Err(Refusal::new(
                        StatusCode::MISDIRECTED_REQUEST,
                        format!(
                            "Host `{}` is not this viewer (use the address it printed)",
                            text.escape_debug()
                        ),
                    ));
                }
            }
        }
    };
    if let Some(origin) = headers.get(ORIGIN) {
        let text = origin.to_str().unwrap_or("");
        if !origin_allowed(bound, host.as_ref(), text) {
            return Err(Refusal::new(
                StatusCode::FORBIDDEN,
                format!(
                    "requests from origin `{}` are refused: only the viewer's own page may \
                     use its API",
                    text.escape_debug()
                ),
            ));
        }
    }
    let reads_only = matches!(*method, Method::GET | Method::HEAD | Method::OPTIONS);
    if !reads_only && !is_json(headers) {
        return Err(Refusal::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            format!("{method} requests must be `Content-Type: application/json`"),
        ));
    }
    Ok(())
}

/// `Content-Type: application/json`, parameters (`; charset=utf-8`) allowed.
fn is_json(headers: &HeaderMap) -> bool {
    headers
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.split(';').next())
        .is_some_and(|m| m.trim().eq_ignore_ascii_case("application/json"))
}

fn port_of(a: &Authority) -> u16 {
    a.port_u16().unwrap_or(80)
}

/// The host of an authority as an IP address, when it is one (`[::1]` → `::1`).
fn ip_of(a: &Authority) -> Option<IpAddr> {
    a.host()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .parse()
        .ok()
}

fn host_allowed(bound: Bound, a: &Authority) -> bool {
    let localhost = a.host().eq_ignore_ascii_case("localhost");
    let ip = ip_of(a);
    let loopback = localhost || ip.is_some_and(|ip| ip.is_loopback());
    match bound {
        Bound::Unknown => loopback,
        Bound::At(addr) => {
            port_of(a) == addr.port()
                && (loopback || ip == Some(addr.ip()) || (!addr.ip().is_loopback() && ip.is_some()))
        }
    }
}

/// Same origin: `http://` and the request's own `Host`; without a `Host`, an origin whose
/// authority would pass the `Host` check.
fn origin_allowed(bound: Bound, host: Option<&Authority>, origin: &str) -> bool {
    let Some(rest) = origin.strip_prefix("http://") else {
        return false;
    };
    let Ok(o) = rest.parse::<Authority>() else {
        return false;
    };
    match host {
        Some(h) => o.host().eq_ignore_ascii_case(h.host()) && port_of(&o) == port_of(h),
        None => host_allowed(bound, &o),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn headers(pairs: &[(&str, &str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.insert(
                axum::http::HeaderName::from_bytes(k.as_bytes()).unwrap(),
                HeaderValue::from_str(v).unwrap(),
            );
        }
        h
    }

    fn status(bound: Bound, method: Method, pairs: &[(&str, &str)]) -> Option<u16> {
        check(bound, &method, &headers(pairs))
            .err()
            .map(|r| r.status.as_u16())
    }

    const JSON: (&str, &str) = ("content-type", "application/json; charset=utf-8");

    #[test]
    fn hosts_must_name_this_server() {
        let lo = Bound::At("127.0.0.1:8080".parse().unwrap());
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST:8080",
            "[::1]:8080",
        ] {
            assert_eq!(status(lo, Method::GET, &[("host", ok)]), None, "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "127.0.0.1:8081",
            "localhost",
            "192.168.1.5:8080",
            "",
        ] {
            assert_eq!(
                status(lo, Method::GET, &[("host", bad)]),
                Some(421),
                "{bad}"
            );
        }
        // Bound to every interface (`--allow-remote`): IP literals, never names. Unknown
        // address: loopback names on any port.
        let any = Bound::At("0.0.0.0:8080".parse().unwrap());
        for (bound, host, want) in [
            (any, "192.168.1.5:8080", None),
            (any, "rebind.example:8080", Some(421)),
            (Bound::Unknown, "localhost:3000", None),
            (Bound::Unknown, "example.org", Some(421)),
        ] {
            let got = status(bound, Method::GET, &[("host", host)]);
            assert_eq!(got, want, "{bound:?} {host}");
        }
    }

    #[test]
    fn origins_must_be_the_page_itself() {
        let lo = Bound::At("127.0.0.1:8080".parse().unwrap());
        let host = ("host", "127.0.0.1:8080");
        let same = ("origin", "http://127.0.0.1:8080");
        assert_eq!(status(lo, Method::POST, &[host, same, JSON]), None);
        assert_eq!(status(lo, Method::POST, &[host, JSON]), None);
        for bad in [
            "http://evil.example",
            "http://localhost:8080",
            "https://127.0.0.1:8080",
            "null",
        ] {
            assert_eq!(
                status(lo, Method::POST, &[host, ("origin", bad), JSON]),
                Some(403),
                "{bad}"
            );
        }
        // Without a Host, the origin itself must pass the Host check.
        for (origin, want) in [
            ("http://localhost:8080", None),
            ("http://evil.example:8080", Some(403)),
        ] {
            let got = status(lo, Method::GET, &[("origin", origin)]);
            assert_eq!(got, want, "{origin}");
        }
    }

    #[test]
    fn state_changes_must_be_json() {
        let b = Bound::Unknown;
        assert_eq!(status(b, Method::POST, &[JSON]), None);
        assert_eq!(status(b, Method::POST, &[]), Some(415));
        for bad in [
            "application/x-www-form-urlencoded",
            "text/plain",
            "multipart/form-data; boundary=x",
            "application/jsonp",
        ] {
            assert_eq!(
                status(b, Method::POST, &[("content-type", bad)]),
                Some(415),
                "{bad}"
            );
        }
        assert_eq!(status(b, Method::GET, &[]), None);
    }
}

//! The viewer's connections: accepted, held and closed by the server itself rather than by
//! `axum::serve`, which keeps an idle connection forever and takes every connection it
//! can. Issue 32 held 1,100 idle TCP connections against a 1,024-file limit and the page
//! stopped answering. Here:
//!
//! - a connection has [`HEADER_TIMEOUT`] to send a request's headers, and so an idle
//!   keep-alive connection is closed after it (hyper's `header_read_timeout`, which runs
//!   while hyper waits for the next request, not while a handler or a websocket runs);
//! - at most [`connection_cap`] connections are held at once (websockets included: the
//!   permit lives in the stream an upgrade keeps); one past it is answered `503` with the
//!   limit and closed at once.

use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use super::limits::{HEADER_TIMEOUT, connection_cap};

/// Accepts connections on `listener` and serves `app` on each, under the limits above,
/// until the task is dropped. A failing `accept` (out of file descriptors) is retried after
/// a pause, as `axum::serve` does.
pub(crate) async fn run(listener: TcpListener, app: Router) -> io::Result<()> {
    let cap = connection_cap();
    let open = Arc::new(Semaphore::new(cap));
    loop {
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            Err(e) if connection_error(&e) => continue,
            Err(_) => {
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        match Arc::clone(&open).try_acquire_owned() {
            Ok(permit) => {
                let held = Held {
                    stream,
                    place: Some(permit),
                    open: Arc::clone(&open),
                    cap,
                };
                tokio::spawn(serve_connection(held, app.clone()));
            }
            Err(_) => {
                tokio::spawn(refuse(stream, cap));
            }
        }
    }
}

/// Errors of one connection that say nothing about the listener.
fn connection_error(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::ConnectionRefused
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::ConnectionReset
    )
}

async fn serve_connection(held: Held, app: Router) {
    let _ = held.stream.set_nodelay(true);
    let io = TokioIo::new(held);
    let mut builder = hyper::server::conn::http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(HEADER_TIMEOUT);
    let _ = builder
        .serve_connection(io, TowerToHyperService::new(app))
        .with_upgrades()
        .await;
}

/// Longest a refused connection is kept to read what its client sent (closing a socket
/// with unread bytes resets it, and the client may lose the 503 before reading it).
const REFUSAL_DRAIN: Duration = Duration::from_millis(500);

/// Answers a connection past the cap with `503` naming the cap, and closes it.
async fn refuse(mut stream: TcpStream, cap: usize) {
    let body = format!(
        "{{\"error\":\"the viewer holds {cap} connections, its limit: try again in a few \
         seconds\",\"kind\":\"too_many_connections\"}}"
    );
    let response = format!(
        "HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\n\
         retry-after: {}\r\nx-content-type-options: nosniff\r\nconnection: close\r\n\
         content-length: {}\r\n\r\n{body}",
        HEADER_TIMEOUT.as_secs(),
        body.len()
    );
    let write = async {
        stream.write_all(response.as_bytes()).await?;
        stream.shutdown().await
    };
    if tokio::time::timeout(REFUSAL_DRAIN, write).await.is_err() {
        return;
    }
    let mut sink = [0u8; 4096];
    let _ = tokio::time::timeout(REFUSAL_DRAIN, async {
        while matches!(stream.read(&mut sink).await, Ok(n) if n > 0) {}
    })
    .await;
}

/// A connection's stream with its place under the cap: the place is given back when the
/// stream is dropped, also after an upgrade to a websocket took it over.
struct Held {
    stream: TcpStream,
    place: Option<OwnedSemaphorePermit>,
    open: Arc<Semaphore>,
    cap: usize,
}

impl Drop for Held {
    /// The last connection of a burst gives the memory of all of them back to the system
    /// ([`return_memory`]).
    fn drop(&mut self) {
        drop(self.place.take());
        if self.open.available_permits() == self.cap {
            return_memory();
        }
    }
}

/// Gives the heap's free memory back to the system, at most once a second. glibc's malloc
/// keeps what a burst of connections freed (docs/reliability.md, "Websockets": 2,000
/// websocket clients left the server at 270–290 MB, where it started at 20 MB, round after
/// round — kept, not leaked); `malloc_trim` returns it.
fn return_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        use std::sync::atomic::{AtomicU64, Ordering};
        /// Last time the heap was trimmed, in milliseconds since the Unix epoch.
        static TRIMMED_AT: AtomicU64 = AtomicU64::new(0);
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64);
        let last = TRIMMED_AT.load(Ordering::Relaxed);
        if now.saturating_sub(last) < 1_000
            || TRIMMED_AT
                .compare_exchange(last, now, Ordering::Relaxed, Ordering::Relaxed)
                .is_err()
        {
            return;
        }
        let trim = || {
            // SAFETY: malloc_trim only walks glibc's own heap; 0 keeps no padding.
            unsafe { libc::malloc_trim(0) };
        };
        match tokio::runtime::Handle::try_current() {
            Ok(rt) => drop(rt.spawn_blocking(trim)),
            Err(_) => trim(),
        }
    }
}

impl AsyncRead for Held {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for Held {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.stream).poll_write(cx, buf)
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.stream).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.stream.is_write_vectored()
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_shutdown(cx)
    }
}

//! An Ethernet hub in user space that impairs what it carries: each port is a TAP device
//! (moved into a host's network namespace as its `eth0`), and every frame read from one port
//! is written to each other port 50 ms later, or dropped with probability 10% (seeded).
//!
//! Why not `tc qdisc add … netem`: this machine's kernel is built without netem
//! (`CONFIG_NET_SCH_NETEM is not set` in /proc/config.gz; `tc` answers "Specified qdisc
//! kind is unknown"), and CI runs on the same kind of machine. The hub gives the same
//! impairment per link: loss and delay on every frame delivered to a host.
#![allow(dead_code)]

use std::collections::VecDeque;
use std::fs::File;
use std::io::{Read, Write};
use std::os::fd::{AsRawFd, FromRawFd};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

/// How the hub impairs each delivered frame.
#[derive(Clone, Copy, Debug)]
pub struct Impairment {
    /// Probability that a frame is not delivered to a port.
    pub loss: f64,
    /// Time between a frame's arrival and its delivery.
    pub delay: Duration,
    /// Seed of the loss draws.
    pub seed: u64,
}

/// What the hub carried.
#[derive(Debug, Default)]
pub struct HubStats {
    pub delivered: AtomicU64,
    pub dropped: AtomicU64,
}

/// A running hub; its threads stop when it is dropped.
pub struct Hub {
    stop: Arc<AtomicBool>,
    pub stats: Arc<HubStats>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

/// Opens TAP device `name` (created by the open; gone when the last descriptor closes).
pub fn open_tap(name: &str) -> File {
    const TUNSETIFF: libc::c_ulong = 0x4004_54ca;
    const IFF_TAP: libc::c_short = 0x0002;
    const IFF_NO_PI: libc::c_short = 0x1000;
    #[repr(C)]
    struct IfReq {
        name: [u8; 16],
        flags: libc::c_short,
        _pad: [u8; 22],
    }
    let path = c"/dev/net/tun";
    // SAFETY: open(2) with a valid C string.
    let fd = unsafe { libc::open(path.as_ptr(), libc::O_RDWR | libc::O_CLOEXEC) };
    assert!(
        fd >= 0,
        "open /dev/net/tun: {}",
        std::io::Error::last_os_error()
    );
    // SAFETY: fd was just opened and is owned by the File from here on.
    let file = unsafe { File::from_raw_fd(fd) };
    let mut req = IfReq {
        name: [0; 16],
        flags: IFF_TAP | IFF_NO_PI,
        _pad: [0; 22],
    };
    assert!(
        name.len() < 16,
        "{name}: interface names have at most 15 bytes"
    );
    req.name[..name.len()].copy_from_slice(name.as_bytes());
    // SAFETY: TUNSETIFF takes a pointer to a struct ifreq (40 bytes), which IfReq lays out.
    let r = unsafe { libc::ioctl(file.as_raw_fd(), TUNSETIFF, &mut req as *mut IfReq) };
    assert!(
        r >= 0,
        "TUNSETIFF {name}: {}",
        std::io::Error::last_os_error()
    );
    file
}

struct Queue {
    frames: Mutex<VecDeque<(Instant, usize, Vec<u8>)>>,
    ready: Condvar,
}

impl Hub {
    /// A hub over `ports` (TAP devices) with `imp` on every delivered frame.
    pub fn start(ports: Vec<File>, imp: Impairment) -> Hub {
        let stop = Arc::new(AtomicBool::new(false));
        let stats = Arc::new(HubStats::default());
        let queue = Arc::new(Queue {
            frames: Mutex::new(VecDeque::new()),
            ready: Condvar::new(),
        });
        let writers: Vec<File> = ports
            .iter()
            .map(|p| p.try_clone().expect("dup a TAP descriptor"))
            .collect();
        let rng = Arc::new(Mutex::new(imp.seed | 1));
        let mut threads = Vec::new();
        for (k, mut port) in ports.into_iter().enumerate() {
            let (stop, queue, rng, stats) = (
                Arc::clone(&stop),
                Arc::clone(&queue),
                Arc::clone(&rng),
                Arc::clone(&stats),
            );
            let n = writers.len();
            // Reads block; a read timeout is not available on a TAP fd, so each reader
            // polls with a 100 ms timeout to see `stop`.
            threads.push(std::thread::spawn(move || {
                let mut buf = vec![0u8; 65536];
                while !stop.load(Ordering::Relaxed) {
                    let mut pfd = libc::pollfd {
                        fd: port.as_raw_fd(),
                        events: libc::POLLIN,
                        revents: 0,
                    };
                    // SAFETY: one valid pollfd.
                    if unsafe { libc::poll(&mut pfd, 1, 100) } <= 0 {
                        continue;
                    }
                    let Ok(len) = port.read(&mut buf) else {
                        break;
                    };
                    let due = Instant::now() + imp.delay;
                    let mut q = queue.frames.lock().unwrap();
                    for to in (0..n).filter(|&to| to != k) {
                        if draw(&rng) < imp.loss {
                            stats.dropped.fetch_add(1, Ordering::Relaxed);
                            continue;
                        }
                        q.push_back((due, to, buf[..len].to_vec()));
                    }
                    queue.ready.notify_one();
                }
            }));
        }
        let (stop2, stats2) = (Arc::clone(&stop), Arc::clone(&stats));
        threads.push(std::thread::spawn(move || {
            let mut writers = writers;
            // The delay is the same for every frame: the queue is in delivery order.
            let mut q = queue.frames.lock().unwrap();
            while !stop2.load(Ordering::Relaxed) {
                let now = Instant::now();
                match q.front() {
                    Some((due, _, _)) if *due <= now => {
                        let (_, to, frame) = q.pop_front().unwrap();
                        let _ = writers[to].write(&frame);
                        stats2.delivered.fetch_add(1, Ordering::Relaxed);
                    }
                    Some((due, _, _)) => {
                        let wait = *due - now;
                        q = queue.ready.wait_timeout(q, wait).unwrap().0;
                    }
                    None => {
                        q = queue
                            .ready
                            .wait_timeout(q, Duration::from_millis(100))
                            .unwrap()
                            .0;
                    }
                }
            }
        }));
        Hub {
            stop,
            stats,
            threads,
        }
    }
}

/// A uniform draw in [0, 1) from the hub's xorshift64 stream.
fn draw(state: &Mutex<u64>) -> f64 {
    let mut s = state.lock().unwrap();
    let mut x = *s;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    *s = x;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

impl Drop for Hub {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

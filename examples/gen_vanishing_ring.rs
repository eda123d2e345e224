//! Writes the nets that stress the vanishing-loop solver: N tokens circling a ring of four
//! places through immediate transitions, so every distribution of the tokens is one vanishing
//! marking and all of them form one loop of C(N+3, 3) markings (N = 30: 5,456; 35: 8,436;
//! 36: 9,139).
//!
//! - default (`ring`): a token leaves the ring now and then (immediate `leave`, weight 0.5), so
//!   the markings fall through loops of every size C(k+3, 3), k = N … 1, before the ring is
//!   empty; an exponential `back` puts all N tokens back;
//! - `--single`: one loop of C(N+3, 3) markings, left only when all N tokens sit in `r3`;
//!   `rest` (exponential) then makes `ready`, where two controllable transitions restart the
//!   ring from `r0` or from `r2`. A `rewards.toml` for `synthesize` is written beside it.
//!
//! ```text
//! cargo run --release --example gen_vanishing_ring -- --tokens 30 --out /tmp/ring30.PNPRO
//! target/release/plan-runner analyze /tmp/ring30.PNPRO
//! cargo run --release --example gen_vanishing_ring -- --tokens 36 --single --out /tmp/loop36/net.PNPRO
//! target/release/plan-runner analyze /tmp/loop36/net.PNPRO
//! target/release/plan-runner synthesize /tmp/loop36/net.PNPRO --rewards /tmp/loop36/rewards.toml
//! ```

use std::path::PathBuf;

use gspn::io::pnpro;
use gspn::net::{Net, NetBuilder, Servers};

/// The four ring places and the ring's immediate transitions (weights differ, so the loop's
/// chain is not symmetric).
fn ring(b: &mut NetBuilder, tokens: u32) -> [gspn::net::PlaceId; 4] {
    let r = [
        b.place("r0", tokens),
        b.place("r1", 0),
        b.place("r2", 0),
        b.place("r3", 0),
    ];
    for (i, w) in [1.0, 2.0, 3.0, 1.5].into_iter().enumerate() {
        let t = b.immediate(format!("step{i}"), w, 1);
        b.moves(r[i], t, r[(i + 1) % 4]);
    }
    r
}

/// Loops of every size: one token at a time leaves the ring.
fn falling(tokens: u32) -> Net {
    let mut b = NetBuilder::new(format!("vanishing_ring_{tokens}"));
    let r = ring(&mut b, tokens);
    let out = b.place("out", 0);
    let leave = b.immediate("leave", 0.5, 1);
    b.moves(r[3], leave, out);
    let back = b.exponential("back", 1.0, Servers::Single);
    b.input(out, back, tokens);
    b.output(back, r[0], tokens);
    b.build().expect("the ring net is well formed")
}

/// One loop, one way out, and a controllable restart.
fn single(tokens: u32) -> Net {
    let mut b = NetBuilder::new(format!("vanishing_loop_{tokens}"));
    let r = ring(&mut b, tokens);
    let (out, ready) = (b.place("out", 0), b.place("ready", 0));
    let done = b.immediate("done", 1.0, 1);
    b.input(r[3], done, tokens);
    b.output(done, out, 1);
    let rest = b.exponential("rest", 1.0, Servers::Single);
    b.moves(out, rest, ready);
    for (name, to) in [("restart_r0", r[0]), ("restart_r2", r[2])] {
        let t = b.immediate(name, 1.0, 1);
        b.input(ready, t, 1);
        b.output(t, to, tokens);
    }
    b.build().expect("the loop net is well formed")
}

const REWARDS: &str = "controllable = [\"restart_r0\", \"restart_r2\"]\nwait = false\n\n\
[places]\n\"out\" = 1\n";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut tokens, mut one, mut out) = (30u32, false, None::<PathBuf>);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--tokens" => tokens = args.next().ok_or("--tokens N")?.parse()?,
            "--single" => one = true,
            "--out" => out = Some(args.next().ok_or("--out FILE")?.into()),
            _ => return Err(format!("unknown argument `{a}`").into()),
        }
    }
    let out = out.ok_or("usage: gen_vanishing_ring --tokens N [--single] --out FILE")?;
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let net = if one { single(tokens) } else { falling(tokens) };
    std::fs::write(&out, pnpro::write(&net))?;
    if one {
        std::fs::write(out.with_file_name("rewards.toml"), REWARDS)?;
    }
    let k = (tokens as u64 + 1) * (tokens as u64 + 2) * (tokens as u64 + 3) / 6;
    println!("{}: largest loop {k} vanishing markings", out.display());
    Ok(())
}

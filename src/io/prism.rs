//! PRISM explicit-state export of a CTMC: `.tra` (transitions with rates), `.sta` (the
//! marking of each state) and `.lab` (`init` and `deadlock` labels), so PRISM
//! (`prism -importtrans N.tra -importstates N.sta -importlabels N.lab -ctmc`) or Storm can
//! check our chain.
//!
//! ```
//! use gspn::analysis::ctmc::Ctmc;
//! use gspn::io::prism::Explicit;
//! let c = Ctmc::from_triplets(2, vec![(0, 1, 1.5), (1, 0, 2.0)]);
//! let markings = vec![vec![1, 0], vec![0, 1]];
//! let e = Explicit::new(&["p1", "p2"], &c, &markings, &[0]);
//! assert_eq!(e.tra(), "2 2\n0 1 1.5\n1 0 2\n");
//! assert_eq!(e.sta(), "(p1,p2)\n0:(1,0)\n1:(0,1)\n");
//! assert_eq!(e.lab(), "0=\"init\" 1=\"deadlock\"\n0: 0\n");
//! ```

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::analysis::ctmc::Ctmc;

/// A chain with its state markings, ready to be written in PRISM's explicit format.
#[derive(Debug)]
pub struct Explicit<'a> {
    names: Vec<String>,
    chain: &'a Ctmc,
    markings: &'a [Vec<u32>],
    initial: &'a [u32],
    rewards: Vec<(String, Vec<f64>)>,
}

impl<'a> Explicit<'a> {
    /// `places` name the marking's components (made into PRISM identifiers: other characters
    /// become `_`); `markings[s]` is state `s`'s marking; `initial` the initial states.
    pub fn new(
        places: &[&str],
        chain: &'a Ctmc,
        markings: &'a [Vec<u32>],
        initial: &'a [u32],
    ) -> Self {
        let names = places.iter().map(|p| identifier(p)).collect();
        Explicit {
            names,
            chain,
            markings,
            initial,
            rewards: Vec::new(),
        }
    }

    /// Adds reward structures, each a name and a rate per state
    /// ([`state_rewards`](crate::analysis::query::state_rewards): impulses folded in at their
    /// rates), written as `PREFIX.NAME.srew` (`prism … -importstaterewards PREFIX.NAME.srew`).
    pub fn with_rewards(mut self, rewards: Vec<(String, Vec<f64>)>) -> Self {
        self.rewards = rewards;
        self
    }

    /// A `.srew` file: `states nonzero`, then `state reward` per nonzero state.
    ///
    /// ```
    /// use gspn::analysis::ctmc::Ctmc;
    /// use gspn::io::prism::Explicit;
    /// let c = Ctmc::from_triplets(2, vec![(0, 1, 1.5), (1, 0, 2.0)]);
    /// let m = vec![vec![1, 0], vec![0, 1]];
    /// assert_eq!(Explicit::new(&["p1", "p2"], &c, &m, &[0]).srew(&[0.0, 2.5]), "2 1\n1 2.5\n");
    /// ```
    pub fn srew(&self, rates: &[f64]) -> String {
        let nonzero = rates.iter().filter(|&&r| r != 0.0).count();
        let mut s = format!("{} {nonzero}\n", self.chain.n);
        for (i, &r) in rates.iter().enumerate() {
            if r != 0.0 {
                let _ = writeln!(s, "{i} {r}");
            }
        }
        s
    }

    /// The `.tra` file: `states transitions`, then `from to rate` per line.
    pub fn tra(&self) -> String {
        let c = self.chain;
        let mut s = String::with_capacity(c.nnz() * 16 + 32);
        let _ = writeln!(s, "{} {}", c.n, c.nnz());
        for i in 0..c.n {
            for (j, q) in c.row(i) {
                let _ = writeln!(s, "{i} {j} {q}");
            }
        }
        s
    }

    /// The `.sta` file: `(p1,p2,..)`, then `state:(k1,k2,..)` per line.
    pub fn sta(&self) -> String {
        let mut s = format!("({})\n", self.names.join(","));
        for (i, m) in self.markings.iter().enumerate() {
            let vals: Vec<String> = m.iter().map(u32::to_string).collect();
            let _ = writeln!(s, "{i}:({})", vals.join(","));
        }
        s
    }

    /// The `.lab` file: label 0 `init`, label 1 `deadlock` (states without exits).
    pub fn lab(&self) -> String {
        let c = self.chain;
        let mut s = String::from("0=\"init\" 1=\"deadlock\"\n");
        for i in 0..c.n {
            let init = self.initial.contains(&(i as u32));
            let dead = c.row_ptr[i] == c.row_ptr[i + 1];
            match (init, dead) {
                (true, true) => {
                    let _ = writeln!(s, "{i}: 0 1");
                }
                (true, false) => {
                    let _ = writeln!(s, "{i}: 0");
                }
                (false, true) => {
                    let _ = writeln!(s, "{i}: 1");
                }
                (false, false) => {}
            }
        }
        s
    }

    /// Writes `PREFIX.tra`, `PREFIX.sta`, `PREFIX.lab` and a `PREFIX.NAME.srew` per reward
    /// structure (NAME made an identifier); returns the paths written.
    pub fn write(&self, prefix: &Path) -> std::io::Result<Vec<PathBuf>> {
        let mut out = Vec::new();
        let mut files = vec![
            ("tra".to_string(), self.tra()),
            ("sta".to_string(), self.sta()),
            ("lab".to_string(), self.lab()),
        ];
        for (name, rates) in &self.rewards {
            files.push((format!("{}.srew", identifier(name)), self.srew(rates)));
        }
        for (ext, text) in files {
            let mut p = prefix.as_os_str().to_owned();
            p.push(".");
            p.push(ext);
            let p = PathBuf::from(p);
            std::fs::write(&p, text)?;
            out.push(p);
        }
        Ok(out)
    }
}

/// A PRISM identifier for a place name: letters, digits and `_`, not starting with a digit.
pub fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

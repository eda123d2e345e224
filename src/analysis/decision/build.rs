//! Building a [`DecisionModel`] from the reachable markings.

use super::{Action, BuildOptions, Controls, DecisionError, DecisionModel, Kind};
use crate::analysis::absorbing::{Absorbed, Target, absorb};
use crate::analysis::state_space::explore::{Arcs, Raw};
use crate::analysis::state_space::packing::MarkingStore;
use crate::analysis::state_space::{Move, Options, search};
use crate::net::{Net, Timing};

/// What a reachable marking becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Tangible,
    Decision,
    Race,
    Eliminated,
}

/// Sums the entries of `v` with equal index (sorted by index).
fn merge(v: &mut Vec<(u32, f64)>) {
    v.sort_unstable_by_key(|&(i, _)| i);
    let mut out: Vec<(u32, f64)> = Vec::with_capacity(v.len());
    for &(i, x) in v.iter() {
        match out.last_mut() {
            Some(last) if last.0 == i => last.1 += x,
            _ => out.push((i, x)),
        }
    }
    *v = out;
}

/// The race of the uncontrolled immediate transitions enabled in vanishing marking `g`:
/// probability ∝ weight (uniform when all weights are 0).
fn race<'r>(net: &Net, raw: &'r Raw, ctrl: &[bool], g: usize) -> Vec<(&'r Move, f64)> {
    let arcs: Vec<(&Move, f64)> = raw
        .moves
        .group(g)
        .iter()
        .filter(|m| m.rate == 0.0 && !ctrl[m.transition.index()])
        .map(|m| match net.transition(m.transition).timing {
            Timing::Immediate { weight, .. } => (m, weight),
            Timing::Exponential { .. } => (m, 0.0),
        })
        .collect();
    let sum: f64 = arcs.iter().map(|&(_, w)| w).sum();
    let k = arcs.len() as f64;
    arcs.into_iter()
        .map(|(m, w)| (m, if sum > 0.0 { w / sum } else { 1.0 / k }))
        .collect()
}

pub(super) fn build(
    net: &Net,
    controls: &Controls,
    opts: &BuildOptions,
) -> Result<DecisionModel, DecisionError> {
    let sopts = Options {
        max_states: opts.max_states,
        threads: opts.threads,
        monitor: opts.monitor.clone(),
        ..Options::default()
    };
    let raw = search(net, &sopts, &sopts.watcher(), controls.wait, Arcs::Store)?;
    let (class, hybrid) = classify(&raw, controls);
    let numbering = Numbering::new(&class, &hybrid);
    let ctrl = &controls.controllable;
    let absorbed = absorb(
        numbering.elim.len(),
        |v, out| {
            for (m, p) in race(net, &raw, ctrl, numbering.elim[v as usize] as usize) {
                out.push((numbering.target(&class, m.to), p));
            }
        },
        |v, out| {
            for (m, p) in race(net, &raw, ctrl, numbering.elim[v as usize] as usize) {
                out.push((m.transition.0, p));
            }
        },
    )
    .map_err(|e| {
        e.into_analysis(|v| {
            let mut mk = vec![0u32; net.place_count()];
            raw.store.get(numbering.elim[v as usize] as usize, &mut mk);
            net.format_marking(&mk)
        })
    })?;
    let emit = Emit {
        net,
        raw: &raw,
        ctrl,
        class: &class,
        hybrid: &hybrid,
        numbering: &numbering,
        absorbed: &absorbed,
    };
    let mut model = emit.states();
    model.initial = match numbering.target(&class, 0) {
        Target::Out(k) => vec![(k, 1.0)],
        Target::In(w) => absorbed.dist[w as usize].clone(),
    };
    keep_markings(&mut model, raw, &class, &numbering.id);
    Ok(model)
}

/// Sorts the reachable markings: tangible ones stay, vanishing ones are decisions (every
/// enabled immediate transition controllable), races kept as states (with WAIT offered
/// beside them, or [`Controls::keep_races`]) or races eliminated. Also says which vanishing
/// markings are *hybrid* (WAIT offered: exponential transitions enabled too).
fn classify(raw: &Raw, controls: &Controls) -> (Vec<Class>, Vec<bool>) {
    let ctrl = &controls.controllable;
    let n = raw.store.len();
    let mut class = vec![Class::Tangible; n];
    let mut hybrid = vec![false; n];
    for g in 0..n {
        if raw.tangible[g] {
            continue;
        }
        let group = raw.moves.group(g);
        let uncontrolled = group
            .iter()
            .any(|m| m.rate == 0.0 && !ctrl[m.transition.index()]);
        hybrid[g] = controls.wait && group.iter().any(|m| m.rate > 0.0);
        class[g] = if !uncontrolled {
            Class::Decision
        } else if hybrid[g] || controls.keep_races {
            Class::Race
        } else {
            Class::Eliminated
        };
    }
    (class, hybrid)
}

/// The states' numbers: kept markings in search order, then the WAIT copies; eliminated
/// markings numbered apart (the local states of the absorbing chain).
struct Numbering {
    /// Per marking: its state (kept) or its local state (eliminated).
    id: Vec<u32>,
    /// The kept markings, by state.
    kept: Vec<u32>,
    /// The eliminated markings, by local state.
    elim: Vec<u32>,
    /// The marking of each WAIT copy, by copy (state `kept.len() + copy`).
    copy_of: Vec<u32>,
    /// Per marking: the state of its WAIT copy (`u32::MAX`: none).
    copy_id: Vec<u32>,
}

impl Numbering {
    fn new(class: &[Class], hybrid: &[bool]) -> Numbering {
        let n = class.len();
        let mut id = vec![u32::MAX; n];
        let (mut kept, mut elim) = (Vec::new(), Vec::new());
        for g in 0..n {
            if class[g] == Class::Eliminated {
                id[g] = elim.len() as u32;
                elim.push(g as u32);
            } else {
                id[g] = kept.len() as u32;
                kept.push(g as u32);
            }
        }
        let mut copy_of: Vec<u32> = Vec::new();
        let mut copy_id = vec![u32::MAX; n];
        for &g in &kept {
            if hybrid[g as usize] {
                copy_id[g as usize] = (kept.len() + copy_of.len()) as u32;
                copy_of.push(g);
            }
        }
        Numbering {
            id,
            kept,
            elim,
            copy_of,
            copy_id,
        }
    }

    /// Where a move into marking `to` lands: a state, or a local state of the chain.
    fn target(&self, class: &[Class], to: u32) -> Target {
        if class[to as usize] == Class::Eliminated {
            Target::In(self.id[to as usize])
        } else {
            Target::Out(self.id[to as usize])
        }
    }
}

/// Writes the states and choices of the model, eliminated races absorbed into the moves
/// that reach them.
struct Emit<'a> {
    net: &'a Net,
    raw: &'a Raw,
    ctrl: &'a [bool],
    class: &'a [Class],
    hybrid: &'a [bool],
    numbering: &'a Numbering,
    absorbed: &'a Absorbed,
}

impl Emit<'_> {
    /// Every kept marking's state, then the WAIT copies (markings still search numbers).
    fn states(&self) -> DecisionModel {
        let Numbering { kept, copy_of, .. } = self.numbering;
        let mut b = Builder::new(self.net, self.raw, self.numbering);
        for (s, &g) in kept.iter().enumerate() {
            let g = g as usize;
            let (kind, exit) = match self.class[g] {
                Class::Tangible => self.delay(&mut b, g, s as u32),
                Class::Decision => {
                    for m in self.raw.moves.group(g).iter().filter(|m| m.rate == 0.0) {
                        b.counts.push((m.transition.0, 1.0));
                        self.add(&mut b, m.to, 1.0);
                        b.choice(Action::Fire(m.transition));
                    }
                    (Kind::Instant, 0.0)
                }
                Class::Race => {
                    for (m, p) in race(self.net, self.raw, self.ctrl, g) {
                        b.counts.push((m.transition.0, p));
                        self.add(&mut b, m.to, p);
                    }
                    b.choice(Action::Race);
                    (Kind::Instant, 0.0)
                }
                Class::Eliminated => unreachable!("eliminated markings are not kept"),
            };
            if self.hybrid[g] {
                b.branches.push((self.numbering.copy_id[g], 1.0));
                b.choice(Action::Wait);
            }
            b.state(g as u32, false, kind, exit);
        }
        for (j, &g) in copy_of.iter().enumerate() {
            let s = (kept.len() + j) as u32;
            let (kind, exit) = self.delay(&mut b, g as usize, s);
            b.state(g, true, kind, exit);
        }
        b.model
    }

    /// A branch with probability `q` into marking `to` (through the absorbed chain when
    /// `to` is eliminated, with the firings counted on the way).
    fn add(&self, b: &mut Builder, to: u32, q: f64) {
        match self.numbering.target(self.class, to) {
            Target::Out(k) => b.branches.push((k, q)),
            Target::In(w) => {
                for &(k, x) in &self.absorbed.dist[w as usize] {
                    b.branches.push((k, q * x));
                }
                for &(t, x) in &self.absorbed.counts[w as usize] {
                    b.counts.push((t, q * x));
                }
            }
        }
    }

    /// State `s` (marking `g`) as a race of its exponential transitions; a dead marking
    /// loops on itself at rate 1.
    fn delay(&self, b: &mut Builder, g: usize, s: u32) -> (Kind, f64) {
        let moves: Vec<&Move> = self
            .raw
            .moves
            .group(g)
            .iter()
            .filter(|m| m.rate > 0.0)
            .collect();
        let exit: f64 = moves.iter().map(|m| m.rate).sum();
        if moves.is_empty() {
            b.branches.push((s, 1.0));
            b.choice(Action::Delay);
            return (Kind::Dead, 1.0);
        }
        for m in moves {
            let q = m.rate / exit;
            b.counts.push((m.transition.0, q));
            self.add(b, m.to, q);
        }
        b.choice(Action::Delay);
        (Kind::Markovian, exit)
    }
}

/// Keeps the markings of kept states only, in the order of their first use, and renumbers
/// the states' markings from search numbers to that store.
fn keep_markings(model: &mut DecisionModel, raw: Raw, class: &[Class], id: &[u32]) {
    let Raw { store, .. } = raw;
    let n = class.len() as u32;
    let new_store = &mut model.store;
    for g in (0..n).filter(|&g| class[g as usize] != Class::Eliminated) {
        new_store.insert(store.packed(g as usize));
    }
    new_store.drop_index();
    for g in model.marking.iter_mut() {
        *g = id[*g as usize];
    }
}

/// Accumulates choices and states in compressed rows.
struct Builder {
    model: DecisionModel,
    branches: Vec<(u32, f64)>,
    counts: Vec<(u32, f64)>,
}

impl Builder {
    /// An empty model for the states `numbering` keeps.
    fn new(net: &Net, raw: &Raw, numbering: &Numbering) -> Builder {
        let total = numbering.kept.len() + numbering.copy_of.len();
        Builder {
            model: DecisionModel {
                places: net.place_count(),
                marking: Vec::with_capacity(total),
                copy: Vec::with_capacity(total),
                kind: Vec::with_capacity(total),
                exit: Vec::with_capacity(total),
                choice_start: vec![0],
                action: Vec::new(),
                branch_start: vec![0],
                to: Vec::new(),
                prob: Vec::new(),
                count_start: vec![0],
                count_t: Vec::new(),
                count_x: Vec::new(),
                initial: Vec::new(),
                copies: numbering.copy_of.len(),
                eliminated: numbering.elim.len(),
                total_markings: numbering.id.len(),
                store: MarkingStore::new(raw.store.layout.clone(), net.place_count()),
            },
            branches: Vec::new(),
            counts: Vec::new(),
        }
    }

    /// Closes a choice with the branches and counts gathered since the last one.
    fn choice(&mut self, action: Action) {
        merge(&mut self.branches);
        merge(&mut self.counts);
        let m = &mut self.model;
        m.action.push(action);
        for &(k, p) in &self.branches {
            m.to.push(k);
            m.prob.push(p);
        }
        m.branch_start.push(m.to.len() as u32);
        for &(t, x) in &self.counts {
            m.count_t.push(t);
            m.count_x.push(x);
        }
        m.count_start.push(m.count_t.len() as u32);
        self.branches.clear();
        self.counts.clear();
    }

    /// Closes a state with the choices added since the last one.
    fn state(&mut self, marking: u32, copy: bool, kind: Kind, exit: f64) {
        let m = &mut self.model;
        m.marking.push(marking);
        m.copy.push(copy);
        m.kind.push(kind);
        m.exit.push(exit);
        m.choice_start.push(m.action.len() as u32);
    }
}

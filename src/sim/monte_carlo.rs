//! Monte-Carlo estimates over independent runs, with 95% confidence intervals.
//!
//! Run `i` of seed `s` is a [`Simulator`] drawing from stream `i` of `s` (so run 0 is the
//! single run `plan-runner simulate --seed s` prints). Each run gives one observation per
//! place (its time-average tokens), per transition (its throughput) and per reward structure
//! asked for (its rate: place rewards integrated over the run's time plus the impulses of
//! the firings, over the run's length — what `run` reports for one run); the estimate is the
//! mean over runs and the interval `mean ± t₀.₉₇₅(R−1) · s/√R` (Student t).
//!
//! Runs are grouped in fixed blocks of consecutive indices; rayon's threads take whole
//! blocks and the blocks are merged in index order, so the result does not depend on the
//! number of threads — bit for bit.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::RunEnd;
use super::{SimError, Simulator};
use crate::analysis::decision::RewardSpec;
use crate::net::Net;
use crate::policy::Policy;
use crate::stats::{Estimate, t_quantile_975};

/// How long each run lasts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Horizon {
    /// Until this virtual time; statistics over `[0, T]`.
    Until(f64),
    /// This many firings; statistics over `[0, time of the last firing]`.
    Steps(u64),
}

/// Runs per block: the unit of work of a thread, merged in order.
const BLOCK: u64 = 8;

/// What a Monte-Carlo experiment estimated.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimates {
    /// Number of runs.
    pub runs: u64,
    /// Firings over all runs.
    pub firings: u64,
    /// Runs that ended in a dead marking.
    pub dead_runs: u64,
    /// Mean length of the observed interval.
    pub mean_time: f64,
    /// Time-average tokens per place, indexed by place.
    pub mean_tokens: Vec<Estimate>,
    /// Throughput per transition, indexed by transition.
    pub throughput: Vec<Estimate>,
    /// Rate of each reward structure ([`MonteCarlo::rewards`]), in the order given.
    pub rewards: Vec<Estimate>,
}

/// A Monte-Carlo experiment: `runs` independent runs of a net under a horizon.
///
/// ```
/// use gspn::net::{NetBuilder, Servers};
/// use gspn::sim::{Horizon, MonteCarlo};
/// let mut b = NetBuilder::new("on-off");
/// let on = b.place("on", 1);
/// let off = b.place("off", 0);
/// let fail = b.exponential("fail", 1.0, Servers::Single);
/// let repair = b.exponential("repair", 3.0, Servers::Single);
/// b.input(on, fail, 1);
/// b.output(fail, off, 1);
/// b.input(off, repair, 1);
/// b.output(repair, on, 1);
/// let net = b.build().unwrap();
/// let est = MonteCarlo::new(&net, Horizon::Until(200.0)).runs(50).seed(1).run().unwrap();
/// assert!(est.mean_tokens[on.index()].contains(0.75)); // availability 3/4
/// ```
#[derive(Clone, Debug)]
pub struct MonteCarlo<'n> {
    net: &'n Net,
    policy: Option<&'n Policy>,
    rewards: &'n [RewardSpec],
    horizon: Horizon,
    runs: u64,
    seed: u64,
    threads: usize,
    max_immediate: u64,
}

impl<'n> MonteCarlo<'n> {
    /// 100 runs of `net` with seed 0, on every available core.
    pub fn new(net: &'n Net, horizon: Horizon) -> Self {
        MonteCarlo {
            net,
            policy: None,
            rewards: &[],
            horizon,
            runs: 100,
            seed: 0,
            threads: 0,
            max_immediate: super::DEFAULT_MAX_IMMEDIATE,
        }
    }

    /// Number of runs (≥ 1).
    pub fn runs(mut self, runs: u64) -> Self {
        self.runs = runs;
        self
    }

    /// The seed; run `i` draws from its stream `i`.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The policy for immediate transitions.
    pub fn policy(mut self, policy: &'n Policy) -> Self {
        self.policy = Some(policy);
        self
    }

    /// Reward structures whose rate each run measures (a plan's `[rewards.NAME]`).
    pub fn rewards(mut self, rewards: &'n [RewardSpec]) -> Self {
        self.rewards = rewards;
        self
    }

    /// Threads to use (0 = rayon's global pool, every available core). Does not change the
    /// result.
    pub fn threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }

    /// Immediate firings allowed at one instant (see [`Simulator::with_max_immediate`]).
    pub fn max_immediate(mut self, max: u64) -> Self {
        self.max_immediate = max;
        self
    }

    /// Runs the experiment. The first error, in run order, ends it.
    pub fn run(&self) -> Result<Estimates, SimError> {
        if self.runs == 0 {
            return Err(SimError::BadArgument("at least one run is needed".into()));
        }
        if let Horizon::Until(t) = self.horizon
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(SimError::BadArgument(format!(
                "time limit {t}: must be a finite number ≥ 0"
            )));
        }
        let blocks = self.runs.div_ceil(BLOCK);
        // The runs share one copy of the net and the policy.
        let net = Arc::new(self.net.clone());
        let policy = self.policy.map(|p| Arc::new(p.clone()));
        // The lowest block that failed so far: blocks after it are skipped, blocks before it
        // still run, so the error kept is the first in run order whatever the scheduling.
        let failed = AtomicU64::new(u64::MAX);
        let run_blocks = || -> Vec<Option<Result<Acc, SimError>>> {
            (0..blocks)
                .into_par_iter()
                .map(|b| {
                    if b > failed.load(Ordering::Relaxed) {
                        return None;
                    }
                    let r = self.block(
                        &net,
                        policy.as_ref(),
                        b * BLOCK,
                        ((b + 1) * BLOCK).min(self.runs),
                    );
                    if r.is_err() {
                        failed.fetch_min(b, Ordering::Relaxed);
                    }
                    Some(r)
                })
                .collect()
        };
        let done = match self.threads {
            0 => run_blocks(),
            n => rayon::ThreadPoolBuilder::new()
                .num_threads(n.min(blocks as usize).max(1))
                .build()
                .map_err(|e| SimError::BadArgument(format!("threads: {e}")))?
                .install(run_blocks),
        };
        // `collect` keeps block order: the merge is the same sum in the same order.
        let mut total = Acc::new(self.observations());
        for r in done.into_iter().map_while(|r| r) {
            total.merge(&r?);
        }
        Ok(total.estimates(self.net.place_count(), self.net.transition_count()))
    }

    /// Observations per run: places, transitions, reward structures.
    fn observations(&self) -> usize {
        self.net.place_count() + self.net.transition_count() + self.rewards.len()
    }

    /// E[tokens] of every place at each of `times` (any order, each ≥ 0), over the runs:
    /// `result[k][p]` is the estimate for place `p` at `times[k]`, with its 95% interval.
    /// The runs are those of [`MonteCarlo::run`] (run `i` draws from stream `i`), each
    /// observed at the times in increasing order; the horizon is not used.
    ///
    /// ```
    /// use gspn::net::{NetBuilder, Servers};
    /// use gspn::sim::{Horizon, MonteCarlo};
    /// let mut b = NetBuilder::new("decay");
    /// let (a, done) = (b.place("a", 1), b.place("done", 0));
    /// let t = b.exponential("t", 1.0, Servers::Single);
    /// b.input(a, t, 1);
    /// b.output(t, done, 1);
    /// let net = b.build().unwrap();
    /// let at = MonteCarlo::new(&net, Horizon::Until(1.0)).runs(400).seed(3).transient(&[0.0, 1.0]).unwrap();
    /// assert_eq!(at[0][a.index()].mean, 1.0);
    /// // E[a at t = 1] = e^{−1}; 400 runs put the mean within 0.1 (four standard errors).
    /// assert!((at[1][a.index()].mean - (-1.0f64).exp()).abs() < 0.1);
    /// ```
    pub fn transient(&self, times: &[f64]) -> Result<Vec<Vec<Estimate>>, SimError> {
        if self.runs == 0 {
            return Err(SimError::BadArgument("at least one run is needed".into()));
        }
        if let Some(t) = times.iter().find(|t| !(t.is_finite() && **t >= 0.0)) {
            return Err(SimError::BadArgument(format!(
                "time {t}: must be a finite number ≥ 0"
            )));
        }
        let places = self.net.place_count();
        let mut order: Vec<usize> = (0..times.len()).collect();
        order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
        let net = Arc::new(self.net.clone());
        let policy = self.policy.map(|p| Arc::new(p.clone()));
        let mut acc = Acc::new(places * times.len());
        let mut x = vec![0.0; places * times.len()];
        for i in 0..self.runs {
            let mut sim = Simulator::new(Arc::clone(&net), self.seed)
                .with_stream(i)
                .with_max_immediate(self.max_immediate);
            if let Some(p) = &policy {
                sim = sim.with_policy(Arc::clone(p));
            }
            for &k in &order {
                sim.run_until(times[k])?;
                for (p, &tokens) in sim.marking().iter().enumerate() {
                    x[k * places + p] = tokens as f64;
                }
            }
            acc.add(&x, sim.firings(), sim.is_dead(), sim.time());
        }
        let est = acc.intervals();
        Ok(est
            .chunks(places.max(1))
            .map(<[Estimate]>::to_vec)
            .take(times.len())
            .collect())
    }

    /// Runs `from..to` in order.
    fn block(
        &self,
        net: &Arc<Net>,
        policy: Option<&Arc<Policy>>,
        from: u64,
        to: u64,
    ) -> Result<Acc, SimError> {
        let mut acc = Acc::new(self.observations());
        let mut x = Vec::with_capacity(self.observations());
        let meter = Meter::new(self.net, self.rewards);
        for i in from..to {
            let mut sim = Simulator::new(Arc::clone(net), self.seed)
                .with_stream(i)
                .with_max_immediate(self.max_immediate);
            if let Some(p) = policy {
                sim = sim.with_policy(Arc::clone(p));
            }
            let (end, rates) = meter.run(&mut sim, self.horizon)?;
            let stats = sim.statistics();
            x.clear();
            x.extend_from_slice(&stats.mean_tokens);
            x.extend_from_slice(&stats.throughput);
            x.extend_from_slice(&rates);
            acc.add(&x, sim.firings(), end == RunEnd::Dead, stats.time);
        }
        Ok(acc)
    }
}

/// The reward structures of an experiment, with each one's impulse per transition.
struct Meter<'n> {
    specs: &'n [RewardSpec],
    impulse: Vec<Vec<f64>>,
}

impl<'n> Meter<'n> {
    fn new(net: &Net, specs: &'n [RewardSpec]) -> Self {
        let impulse = specs.iter().map(|s| s.impulses(net)).collect();
        Meter { specs, impulse }
    }

    /// Runs `sim` to the horizon and returns how it ended and each structure's rate over
    /// the run. Without structures, the simulator's own loop; with some, the same steps
    /// one at a time, the place rate of each marking integrated over the time it holds.
    fn run(&self, sim: &mut Simulator, horizon: Horizon) -> Result<(RunEnd, Vec<f64>), SimError> {
        if self.specs.is_empty() {
            let end = match horizon {
                Horizon::Until(t) => sim.run_until(t)?,
                Horizon::Steps(n) => sim.run_steps(n)?,
            };
            return Ok((end, Vec::new()));
        }
        let rate_of = |sim: &Simulator| -> Vec<f64> {
            self.specs
                .iter()
                .map(|s| s.place_rate(sim.marking()))
                .collect()
        };
        let mut earned = vec![0.0; self.specs.len()];
        let mut rate = rate_of(sim);
        let mut since = sim.time();
        let mut fired = 0;
        let mut end = RunEnd::Limit;
        loop {
            let step = match horizon {
                Horizon::Until(t) => sim.step_until(t)?,
                Horizon::Steps(n) if fired < n => sim.step()?,
                Horizon::Steps(_) => break,
            };
            let Some(step) = step else {
                if let Horizon::Until(t) = horizon {
                    end = sim.run_until(t)?;
                } else {
                    end = RunEnd::Dead;
                }
                break;
            };
            fired += 1;
            for (k, e) in earned.iter_mut().enumerate() {
                *e += rate[k] * (step.time - since) + self.impulse[k][step.transition.index()];
            }
            rate = rate_of(sim);
            since = step.time;
        }
        let time = sim.time();
        for (k, e) in earned.iter_mut().enumerate() {
            *e += rate[k] * (time - since);
        }
        let rates = earned
            .iter()
            .map(|&e| if time > 0.0 { e / time } else { 0.0 })
            .collect();
        Ok((end, rates))
    }
}

/// [`MonteCarlo`] in one call: `runs` runs of `net` (no policy) from `seed`.
pub fn monte_carlo(
    net: &Net,
    runs: u64,
    horizon: Horizon,
    seed: u64,
) -> Result<Estimates, SimError> {
    MonteCarlo::new(net, horizon).runs(runs).seed(seed).run()
}

/// Running means and sums of squared deviations (Welford; blocks merged with Chan's
/// formula).
#[derive(Clone, Debug)]
struct Acc {
    n: u64,
    mean: Vec<f64>,
    m2: Vec<f64>,
    firings: u64,
    dead: u64,
    time: f64,
}

impl Acc {
    fn new(len: usize) -> Acc {
        Acc {
            n: 0,
            mean: vec![0.0; len],
            m2: vec![0.0; len],
            firings: 0,
            dead: 0,
            time: 0.0,
        }
    }

    fn add(&mut self, x: &[f64], firings: u64, dead: bool, time: f64) {
        self.n += 1;
        let n = self.n as f64;
        for ((m, s), &v) in self.mean.iter_mut().zip(&mut self.m2).zip(x) {
            let d = v - *m;
            *m += d / n;
            *s += d * (v - *m);
        }
        self.firings += firings;
        self.dead += dead as u64;
        self.time += time;
    }

    fn merge(&mut self, o: &Acc) {
        if o.n == 0 {
            return;
        }
        let (na, nb) = (self.n as f64, o.n as f64);
        let n = na + nb;
        for i in 0..self.mean.len() {
            let d = o.mean[i] - self.mean[i];
            self.mean[i] += d * nb / n;
            self.m2[i] += o.m2[i] + d * d * na * nb / n;
        }
        self.n += o.n;
        self.firings += o.firings;
        self.dead += o.dead;
        self.time += o.time;
    }

    /// The mean of each component with its 95% Student-t half width (NaN for one run).
    fn intervals(&self) -> Vec<Estimate> {
        let n = self.n as f64;
        let t = if self.n >= 2 {
            t_quantile_975(self.n - 1)
        } else {
            f64::NAN
        };
        self.mean
            .iter()
            .zip(&self.m2)
            .map(|(&mean, &m2)| Estimate {
                mean,
                half_width: t * (m2.max(0.0) / (n - 1.0)).sqrt() / n.sqrt(),
            })
            .collect()
    }

    fn estimates(&self, places: usize, transitions: usize) -> Estimates {
        let n = self.n as f64;
        let est = self.intervals();
        Estimates {
            runs: self.n,
            firings: self.firings,
            dead_runs: self.dead,
            mean_time: self.time / n,
            mean_tokens: est[..places].to_vec(),
            throughput: est[places..places + transitions].to_vec(),
            rewards: est[places + transitions..].to_vec(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_blocks_equal_one_pass() {
        let xs: Vec<f64> = (0..37).map(|i| ((i * 7919) % 101) as f64 / 10.0).collect();
        let mut one = Acc::new(1);
        for &x in &xs {
            one.add(&[x], 1, false, 1.0);
        }
        let mut merged = Acc::new(1);
        for chunk in xs.chunks(8) {
            let mut b = Acc::new(1);
            for &x in chunk {
                b.add(&[x], 1, false, 1.0);
            }
            merged.merge(&b);
        }
        assert!((one.mean[0] - merged.mean[0]).abs() < 1e-12);
        assert!((one.m2[0] - merged.m2[0]).abs() < 1e-9);
        assert_eq!(merged.n, 37);
    }
}

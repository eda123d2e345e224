//! Analysis: state space, properties, CTMC steady state and transient, measures.
//!
//! (Being written.) [`ctmc`] holds the continuous-time Markov chain and its solvers; the
//! tangible reachability graph is built from a [`Net`](crate::net::Net) and handed to it.
//!
//! - [`state_space`]: the tangible reachability graph ([`StateSpace`](state_space::StateSpace)),
//!   [`vanishing`] markings eliminated (loops of immediate transitions by the one solver in
//!   `absorbing`, whose LU lives in `linear`: dense when small, sparse above); [`coverability`] (Karp–Miller) stops unbounded nets;
//!   [`properties`] (bounds, deadlocks, liveness, reversibility) and [`invariants`] (Farkas)
//!   read it; [`scc`] is the shared Tarjan.
//! - [`ctmc`]: the chain over tangible states and its solvers (steady state by sparse LU or
//!   Gauss–Seidel, limiting distribution of non-ergodic chains, transient by uniformization);
//!   [`measures`] turns a distribution into mean tokens, throughputs, waiting times and
//!   predicate probabilities ([`Solver`](measures::Solver)).
//! - [`under_policy`]: a plan's net analysed under its policy, with its reward rates
//!   (`analyze PLAN`; the bare net when the plan has no policy).
//! - [`query`]: questions in Storm's and PRISM's property syntax (`P=? [F<=600 done=1]`,
//!   `T=? [F done=1]`, `S=? [..]`, rewards, `Pmax=?`), read on the full graph.
//! - [`report`]: the typed report of all this — what `plan-runner analyze --json` prints and
//!   what the viewer's analysis panel shows.
//!
//! ```
//! use gspn::analysis::measures::{Solver, SolverOptions};
//! use gspn::analysis::state_space::{Options, StateSpace};
//! use gspn::net::{NetBuilder, Servers};
//! // A machine that breaks (rate 0.1) and is repaired (rate 2).
//! let mut b = NetBuilder::new("machine");
//! let (up, down) = (b.place("Up", 1), b.place("Down", 0));
//! let fail = b.exponential("fail", 0.1, Servers::Single);
//! let repair = b.exponential("repair", 2.0, Servers::Single);
//! b.input(up, fail, 1); b.output(fail, down, 1);
//! b.input(down, repair, 1); b.output(repair, up, 1);
//! let net = b.build().unwrap();
//! let space = StateSpace::build(&net, &Options::default()).unwrap();
//! let solver = Solver::new(&net, &space);
//! let steady = solver.steady_state(&SolverOptions::default()).unwrap();
//! let m = solver.measures(&steady.pi);
//! assert!((m.mean_tokens[up.index()] - 2.0 / 2.1).abs() < 1e-12);
//! assert!((m.throughput[fail.index()] - 0.2 / 2.1).abs() < 1e-12);
//! let at_1 = &solver.transient(&[1.0], &Default::default()).unwrap()[0];
//! assert!((solver.measures(at_1).mean_tokens[up.index()]
//!     - (2.0 + 0.1 * (-2.1f64).exp()) / 2.1).abs() < 1e-11);
//! ```

pub(crate) mod absorbing;
pub mod coverability;
pub mod ctmc;
pub mod decision;
pub mod invariants;
pub(crate) mod linear;
pub mod measures;
pub mod properties;
pub mod query;
pub mod report;
pub mod scc;
pub mod state_space;
pub mod under_policy;
pub(crate) mod vanishing;

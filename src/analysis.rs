//! Analysis: state space, properties, CTMC steady state and transient, measures.
//!
//! (Being written.) [`ctmc`] holds the continuous-time Markov chain and its solvers; the
//! tangible reachability graph is built from a [`Net`](crate::net::Net) and handed to it.
//!
//! - [`state_space`]: the tangible reachability graph ([`StateSpace`](state_space::StateSpace)),
//!   [`vanishing`] markings eliminated; [`coverability`] (Karp–Miller) stops unbounded nets;
//!   [`properties`] (bounds, deadlocks, liveness, reversibility) and [`invariants`] (Farkas)
//!   read it; [`scc`] is the shared Tarjan.
//! - [`ctmc`]: the chain over tangible states and its solvers (steady state by sparse LU or
//!   Gauss–Seidel, limiting distribution of non-ergodic chains, transient by uniformization);
//!   [`measures`] turns a distribution into mean tokens, throughputs, waiting times and
//!   predicate probabilities ([`Solver`](measures::Solver)).

pub mod coverability;
pub mod ctmc;
pub mod invariants;
pub mod measures;
pub mod properties;
pub mod scc;
pub mod state_space;
pub mod vanishing;

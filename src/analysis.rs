//! Analysis: state space, properties, CTMC steady state and transient, measures.
//!
//! (Being written.) [`ctmc`] holds the continuous-time Markov chain and its solvers; the
//! tangible reachability graph is built from a [`Net`](crate::net::Net) and handed to it.

pub mod ctmc;

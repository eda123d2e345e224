//! Behavioural properties of a net read off its state space.

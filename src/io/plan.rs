//! Plan files (TOML): the net, roles of places, policy, stop conditions (being written).

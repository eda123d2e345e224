//! The actor runtime: supervisor, agents, places, actions, events, journal (being written).

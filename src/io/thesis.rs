//! The thesis framework's JSON execution inputs, turned into plans (being written).

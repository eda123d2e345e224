//! The token game: exact GSPN semantics on virtual time, seeded (being written).

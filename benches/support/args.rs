//! The command line of a bench program, as `std::env::args()` gives it but without the
//! `--bench` flag that `cargo bench` appends to every bench target's arguments
//! (`cargo bench --bench scale -- 1000` runs `scale 1000 --bench`).

/// The program's arguments, the program's name first, `--bench` left out.
pub fn args() -> impl Iterator<Item = String> {
    std::env::args().filter(|a| a != "--bench")
}

//! Groups of nodes the automatic layout keeps together: the places and transitions of one
//! location or one robot, known by a name part they share — `Mop_L2`, `Mopping_L2`,
//! `Go_L2_L3` and `L2` are location `L2`'s; `p3:Decide_L2` too; `Wait_r1` is robot `r1`'s.
//!
//! A name part counts when it is a few letters then digits (`L2`, `r1`, `loc12`) and at
//! least two names have it; a node's group is the first such part after the name's first
//! (`Go_L2_L3`: `L2`, where the robot is), or the name itself when it is one (`L2`). Nets
//! whose names give fewer than two groups, or leave most nodes in none (MCC's `flag_0_1`:
//! no part of letters and digits), are laid out as before.

use std::collections::HashMap;

/// Most letters before the digits of a group's name (`loc12`).
const MAX_LETTERS: usize = 3;

/// Whether `part` looks like a location's or a robot's name: 1–3 letters, then digits.
fn key_like(part: &str) -> bool {
    let letters = part.chars().take_while(char::is_ascii_alphabetic).count();
    (1..=MAX_LETTERS).contains(&letters)
        && part.len() > letters
        && part[letters..].chars().all(|c| c.is_ascii_digit())
}

fn parts(name: &str) -> Vec<&str> {
    name.split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|p| !p.is_empty())
        .collect()
}

/// The group of each name (indexes into the groups, in order of first appearance), or
/// `None` when the names do not form groups (see the module's doc).
pub(super) fn groups<'a>(names: impl Iterator<Item = &'a str>) -> Option<Vec<Option<usize>>> {
    let names: Vec<Vec<&str>> = names.map(parts).collect();
    let mut count: HashMap<&str, usize> = HashMap::new();
    for ps in &names {
        let mut seen: Vec<&str> = ps.iter().copied().filter(|p| key_like(p)).collect();
        seen.sort_unstable();
        seen.dedup();
        for p in seen {
            *count.entry(p).or_default() += 1;
        }
    }
    let shared = |p: &&str| key_like(p) && count.get(p).is_some_and(|&n| n >= 2);
    let mut index: HashMap<&str, usize> = HashMap::new();
    let of: Vec<Option<usize>> = names
        .iter()
        .map(|ps| {
            let key = match ps.as_slice() {
                [only] => Some(*only).filter(|p| shared(p)),
                [_, rest @ ..] => rest.iter().copied().find(|p| shared(p)),
                [] => None,
            }?;
            let next = index.len();
            Some(*index.entry(key).or_insert(next))
        })
        .collect();
    let grouped = of.iter().filter(|g| g.is_some()).count();
    (index.len() >= 2 && 2 * grouped >= of.len()).then_some(of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_and_robots_are_found_in_the_names() {
        let names = [
            "L1",
            "Mop_L1",
            "Go_L1_L2",
            "L2",
            "Mop_L2",
            "p3:Decide_L2",
            "Wait_r1",
            "Done_r1",
            "start",
        ];
        let g = groups(names.iter().copied()).unwrap();
        assert_eq!(
            g,
            [
                Some(0),
                Some(0),
                Some(0),
                Some(1),
                Some(1),
                Some(1),
                Some(2),
                Some(2),
                None
            ]
        );
        // MCC's names: digits only after the first part.
        assert_eq!(groups(["flag_0_1", "flag_1_1", "p_0_0"].into_iter()), None);
        // One group is no grouping.
        assert_eq!(groups(["a_L1", "b_L1", "c"].into_iter()), None);
    }
}

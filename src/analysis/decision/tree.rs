//! A deterministic policy table compressed into a decision tree over token counts, written as
//! partial [`Rule`]s that the policy lookup applies in order (first match wins).
//!
//! Each inner node tests `m(p) == k`. The rules of the "equal" subtree come first, each with
//! `p = k` added to its pattern, then those of the "different" subtree. A rule listed before
//! a marking's own leaf left that marking's path at a node where the rule took "equal" and
//! the marking "different", so it does not match: the first rule that matches a marking of
//! the table is its own leaf, which chooses the table's transition. The tree is grown
//! greedily (the split with the least weighted Gini impurity), so it is exact on every
//! marking of the table by construction; [`compress`] checks it anyway.

use rustc_hash::FxHashMap;

use crate::net::{PlaceId, TransitionId};
use crate::policy::{Pattern, Rule};

/// Compresses `table` (marking → transition) into partial rules, in lookup order.
pub fn compress(table: &[(Vec<u32>, TransitionId)]) -> Vec<Rule> {
    let mut rules = Vec::new();
    let idx: Vec<usize> = (0..table.len()).collect();
    grow(table, idx, &mut Vec::new(), &mut rules);
    debug_assert!(table.iter().all(|(m, t)| {
        rules
            .iter()
            .find(|r| r.pattern.matches(m))
            .is_some_and(|r| r.choose == vec![(*t, 1.0)])
    }));
    rules
}

fn gini(counts: &FxHashMap<u32, usize>, n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let n = n as f64;
    1.0 - counts
        .values()
        .map(|&c| (c as f64 / n).powi(2))
        .sum::<f64>()
}

fn grow(
    table: &[(Vec<u32>, TransitionId)],
    idx: Vec<usize>,
    path: &mut Vec<(PlaceId, u32)>,
    rules: &mut Vec<Rule>,
) {
    let Some(&first) = idx.first() else { return };
    let label = table[first].1;
    if idx.iter().all(|&i| table[i].1 == label) {
        rules.push(Rule {
            pattern: Pattern::Partial(path.clone()),
            choose: vec![(label, 1.0)],
        });
        return;
    }
    let places = table[first].0.len();
    let mut total: FxHashMap<u32, usize> = FxHashMap::default();
    for &i in &idx {
        *total.entry(table[i].1.0).or_insert(0) += 1;
    }
    let mut best: Option<(f64, usize, u32)> = None;
    for p in 0..places {
        if path.iter().any(|&(q, _)| q.index() == p) {
            continue;
        }
        // Per value of m(p): label counts.
        let mut by_value: FxHashMap<u32, FxHashMap<u32, usize>> = FxHashMap::default();
        for &i in &idx {
            *by_value
                .entry(table[i].0[p])
                .or_default()
                .entry(table[i].1.0)
                .or_insert(0) += 1;
        }
        if by_value.len() < 2 {
            continue;
        }
        let mut values: Vec<u32> = by_value.keys().copied().collect();
        values.sort_unstable();
        for k in values {
            let yes = &by_value[&k];
            let ny: usize = yes.values().sum();
            let mut no = total.clone();
            for (l, c) in yes {
                let e = no.get_mut(l).expect("a label of the subset");
                *e -= c;
            }
            no.retain(|_, c| *c > 0);
            let nn = idx.len() - ny;
            let score = (ny as f64 * gini(yes, ny) + nn as f64 * gini(&no, nn)) / idx.len() as f64;
            if best.is_none_or(|(b, _, _)| score < b - 1e-15) {
                best = Some((score, p, k));
            }
        }
    }
    let Some((_, p, k)) = best else {
        // Identical markings with different labels cannot come from a table; keep the first.
        rules.push(Rule {
            pattern: Pattern::Partial(path.clone()),
            choose: vec![(label, 1.0)],
        });
        return;
    };
    let (yes, no): (Vec<usize>, Vec<usize>) = idx.into_iter().partition(|&i| table[i].0[p] == k);
    path.push((PlaceId(p as u32), k));
    grow(table, yes, path, rules);
    path.pop();
    grow(table, no, path, rules);
}

//! Strongly connected components (Tarjan, iterative: no recursion, so a chain of millions of
//! states does not overflow the stack).
//!
//! ```
//! use gspn::analysis::scc::tarjan;
//! // 0 → 1 → 2 → 1, 2 → 3
//! let succ = [vec![1], vec![2], vec![1, 3], vec![]];
//! let sccs = tarjan(4, |v, out| out.extend_from_slice(&succ[v as usize]));
//! assert_eq!(sccs.count, 3);
//! assert_eq!(sccs.component[1], sccs.component[2]);
//! // Components are numbered sinks first: {3} is component 0.
//! assert_eq!(sccs.component[3], 0);
//! assert_eq!(sccs.bottom(|v, out| out.extend_from_slice(&succ[v as usize])), vec![true, false, false]);
//! ```

/// The strongly connected components of a graph over vertices `0..n`.
#[derive(Clone, Debug, Default)]
pub struct Sccs {
    /// Number of components.
    pub count: usize,
    /// Component of each vertex. Components are numbered in the order Tarjan completes them,
    /// which is a reverse topological order: every edge leaving component `c` goes to a
    /// component numbered below `c`.
    pub component: Vec<u32>,
}

impl Sccs {
    /// The vertices of each component, components in numbering order.
    pub fn members(&self) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.count];
        for (v, &c) in self.component.iter().enumerate() {
            out[c as usize].push(v as u32);
        }
        out
    }

    /// For each component, whether it is a bottom component (no edge leaves it).
    /// `successors(v, out)` appends the successors of `v` to `out`.
    pub fn bottom(&self, mut successors: impl FnMut(u32, &mut Vec<u32>)) -> Vec<bool> {
        let mut bottom = vec![true; self.count];
        let mut buf = Vec::new();
        for (v, &c) in self.component.iter().enumerate() {
            if !bottom[c as usize] {
                continue;
            }
            buf.clear();
            successors(v as u32, &mut buf);
            if buf.iter().any(|&w| self.component[w as usize] != c) {
                bottom[c as usize] = false;
            }
        }
        bottom
    }
}

const UNVISITED: u32 = u32::MAX;

/// Tarjan's algorithm over vertices `0..n`; `successors(v, out)` appends the successors of
/// `v` to `out` (duplicates and self-loops are fine).
pub fn tarjan(n: usize, mut successors: impl FnMut(u32, &mut Vec<u32>)) -> Sccs {
    let mut index = vec![UNVISITED; n];
    let mut low = vec![0u32; n];
    let mut component = vec![UNVISITED; n];
    let mut stack: Vec<u32> = Vec::new();
    // Pending successors of the vertices on the DFS path; frames are (vertex, start, next, end).
    let mut pending: Vec<u32> = Vec::new();
    let mut frames: Vec<(u32, usize, usize, usize)> = Vec::new();
    let mut next_index = 0u32;
    let mut count = 0u32;
    for root in 0..n as u32 {
        if index[root as usize] != UNVISITED {
            continue;
        }
        let mut visit = |v: u32,
                         index: &mut Vec<u32>,
                         low: &mut Vec<u32>,
                         stack: &mut Vec<u32>,
                         pending: &mut Vec<u32>,
                         frames: &mut Vec<(u32, usize, usize, usize)>| {
            index[v as usize] = next_index;
            low[v as usize] = next_index;
            next_index += 1;
            stack.push(v);
            let start = pending.len();
            successors(v, pending);
            frames.push((v, start, start, pending.len()));
        };
        visit(
            root,
            &mut index,
            &mut low,
            &mut stack,
            &mut pending,
            &mut frames,
        );
        while let Some(&(v, _, next, end)) = frames.last() {
            if next < end {
                let w = pending[next];
                let top = frames.len() - 1;
                frames[top].2 += 1;
                if index[w as usize] == UNVISITED {
                    visit(
                        w,
                        &mut index,
                        &mut low,
                        &mut stack,
                        &mut pending,
                        &mut frames,
                    );
                } else if component[w as usize] == UNVISITED {
                    // On the stack: a back or cross edge inside the current component.
                    low[v as usize] = low[v as usize].min(index[w as usize]);
                }
                continue;
            }
            let (_, start, _, _) = frames.pop().expect("a frame is on the stack");
            pending.truncate(start);
            if low[v as usize] == index[v as usize] {
                loop {
                    let w = stack.pop().expect("v is on the stack");
                    component[w as usize] = count;
                    if w == v {
                        break;
                    }
                }
                count += 1;
            }
            if let Some(&(parent, _, _, _)) = frames.last() {
                low[parent as usize] = low[parent as usize].min(low[v as usize]);
            }
        }
    }
    Sccs {
        count: count as usize,
        component,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_chain_does_not_recurse() {
        let n = 1_000_000;
        let sccs = tarjan(n, |v, out| {
            if (v as usize) + 1 < n {
                out.push(v + 1)
            }
        });
        assert_eq!(sccs.count, n);
        assert_eq!(sccs.component[n - 1], 0);
    }

    #[test]
    fn cycle_is_one_component() {
        let sccs = tarjan(5, |v, out| out.push((v + 1) % 5));
        assert_eq!(sccs.count, 1);
        assert_eq!(sccs.bottom(|v, out| out.push((v + 1) % 5)), vec![true]);
    }
}

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
    /// The vertices of each component, components in numbering order (one flat array: no
    /// allocation per component).
    pub fn members(&self) -> Members {
        let mut start = vec![0u32; self.count + 1];
        for &c in &self.component {
            start[c as usize + 1] += 1;
        }
        for c in 0..self.count {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut vertices = vec![0u32; self.component.len()];
        for (v, &c) in self.component.iter().enumerate() {
            vertices[fill[c as usize] as usize] = v as u32;
            fill[c as usize] += 1;
        }
        Members { start, vertices }
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

/// The vertices of each component ([`Sccs::members`]), in increasing order within each.
#[derive(Clone, Debug, Default)]
pub struct Members {
    start: Vec<u32>,
    vertices: Vec<u32>,
}

impl Members {
    /// Number of components.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// Whether there are no components.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The components' vertex lists in numbering order.
    pub fn iter(&self) -> MembersIter<'_> {
        self.into_iter()
    }
}

impl<'a> IntoIterator for &'a Members {
    type Item = &'a [u32];
    type IntoIter = MembersIter<'a>;

    fn into_iter(self) -> MembersIter<'a> {
        MembersIter {
            members: self,
            next: 0,
        }
    }
}

/// Iterator over the components of [`Members`].
#[derive(Clone, Debug)]
pub struct MembersIter<'a> {
    members: &'a Members,
    next: usize,
}

impl<'a> Iterator for MembersIter<'a> {
    type Item = &'a [u32];

    fn next(&mut self) -> Option<&'a [u32]> {
        if self.next >= self.members.len() {
            return None;
        }
        self.next += 1;
        Some(&self.members[self.next - 1])
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let rest = self.members.len() - self.next;
        (rest, Some(rest))
    }
}

impl ExactSizeIterator for MembersIter<'_> {}

impl std::ops::Index<usize> for Members {
    type Output = [u32];

    fn index(&self, c: usize) -> &[u32] {
        &self.vertices[self.start[c] as usize..self.start[c + 1] as usize]
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

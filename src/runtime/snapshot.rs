//! The marking handed to actions: one shared snapshot per firing count, from a small pool.

use std::sync::Arc;

use crate::net::Marking;

/// Retired marking snapshots kept for reuse.
const POOL: usize = 16;

/// The current snapshot and the retired ones.
#[derive(Debug, Default)]
pub(crate) struct Snapshots {
    current: Option<(u64, Arc<Marking>)>,
    pool: Vec<Arc<Marking>>,
}

impl Snapshots {
    /// The marking for an action's context: one snapshot per firing count, shared by the
    /// actions started in between. Retired snapshots go to a small pool and are overwritten
    /// once no action holds them any more: a large marking is copied, not allocated, at
    /// every firing (allocating it cost half the firing rate on a 1000-place ring).
    pub(crate) fn get(&mut self, firings: u64, m: &Marking) -> Arc<Marking> {
        if let Some((f, s)) = &self.current
            && *f == firings
        {
            return Arc::clone(s);
        }
        if let Some((_, old)) = self.current.take()
            && self.pool.len() < POOL
        {
            self.pool.push(old);
        }
        let free = self.pool.iter_mut().position(|a| Arc::get_mut(a).is_some());
        let s = match free {
            Some(i) => {
                let mut a = self.pool.swap_remove(i);
                if let Some(x) = Arc::get_mut(&mut a) {
                    x.copy_from_slice(m);
                }
                a
            }
            None => Arc::new(m.clone()),
        };
        self.current = Some((firings, Arc::clone(&s)));
        s
    }
}

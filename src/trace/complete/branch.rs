//! The branch-and-bound over tuples of hierarchy nodes.

use super::Search;
use super::bounds::pruned;
use super::result::Arrival;

impl Search<'_> {
    /// [`pruned`] for the places in `self.sc.places`.
    pub(super) fn pruned(&self) -> bool {
        let g = &self.g;
        pruned(&self.sc.places, g.source, g.receiver, g.slowness)
    }

    /// The branch-and-bound from the tuple of roots.
    pub(super) fn run(&mut self, out: &mut Vec<Arrival>) {
        let k = self.g.k();
        if k == 0 {
            self.solve_leaf_choice(&[], 0, out);
            return;
        }
        let mut stack = std::mem::take(&mut self.sc.stack);
        let mut tuple = std::mem::take(&mut self.sc.tuple);
        let mut segs = std::mem::take(&mut self.sc.segs);
        stack.clear();
        stack.resize(k, 0);
        self.branch_and_bound(&mut stack, &mut tuple, &mut segs, out);
        (self.sc.stack, self.sc.tuple, self.sc.segs) = (stack, tuple, segs);
    }

    /// The search's loop, on the tuples in `stack` (scratch `tuple` and `segs`, `k` long).
    fn branch_and_bound(
        &mut self,
        stack: &mut Vec<u32>,
        tuple: &mut [u32],
        segs: &mut [usize],
        out: &mut Vec<Arrival>,
    ) {
        let k = self.g.k();
        while !stack.is_empty() {
            let at = stack.len() - k;
            tuple.copy_from_slice(&stack[at..]);
            stack.truncate(at);
            self.stats.tuples += 1;
            if self.stats.tuples > self.max_tuples {
                self.stats.complete = false;
                return;
            }
            self.sc.places.clear();
            for (i, &n) in tuple.iter().enumerate() {
                let mut place = self.hierarchies[i].nodes[n as usize].place;
                place.interface = self.g.steps[i].interface;
                self.sc.places.push(place);
            }
            if self.pruned() {
                continue;
            }
            // Split the widest node that has halves.
            let split = (0..k)
                .filter_map(|i| {
                    let node = &self.hierarchies[i].nodes[tuple[i] as usize];
                    node.kids.map(|kids| (i, kids, node.bbox.diagonal()))
                })
                .max_by(|a, b| a.2.total_cmp(&b.2).then(b.0.cmp(&a.0)));
            match split {
                Some((i, [l, r], _)) => {
                    for child in [r, l] {
                        stack.extend_from_slice(tuple);
                        let at = stack.len() - k + i;
                        stack[at] = child;
                    }
                }
                None => {
                    for (i, &n) in tuple.iter().enumerate() {
                        segs[i] = self.hierarchies[i].nodes[n as usize].first as usize;
                    }
                    for held in 0..(1usize << k) {
                        self.solve_leaf_choice(segs, held, out);
                    }
                }
            }
        }
    }
}

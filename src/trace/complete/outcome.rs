//! How an assignment's solve ends: what the minimisation (`minimise.rs`) and the collapses
//! and stalls (`collapse.rs`, `smoothed.rs`) tell each other and the leaf (`leaf.rs`).

use crate::trace::Threshold;

/// How an assignment's solve ended.
pub(super) enum Settled {
    /// At the minimiser (to the tolerance or round-off).
    Yes,
    /// At a minimiser where a leg vanished, decided exactly (the subgradient at a collapse
    /// between two interactions, an end point exactly on its interaction's line): no
    /// stationary path (the classifier's `coincident`).
    Collapsed,
    /// Taken to approach a minimiser where a leg vanishes or runs along its interface by a
    /// rule with a threshold: no stationary path found, but not a proof.
    Threshold(Threshold),
    /// At the minimum over the segments, with a point at an end of its segment that `T`
    /// pushes outwards: `T` being convex, no stationary point lies inside the segments.
    Outside,
    /// Not settled (the search is then not complete).
    No,
}

/// What a collapse or a stall of an assignment's solve leads to.
pub(super) enum Kinked {
    /// The solve ends so.
    Settled(Settled),
    /// Points were pinned at a collapse, or moved away from one that is not the minimum:
    /// the solve goes on.
    Restarted,
}

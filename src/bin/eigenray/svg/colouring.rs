//! What colours the rays (time, path or sequence): the choice the legend, the colour bar
//! and the colours all read.

/// What gives a ray its colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Colouring {
    /// Travel time, on viridis, with a colour bar.
    #[default]
    Time,
    /// The path, with a legend of path names (a search arrival, which has no path: its step
    /// sequence).
    Path,
    /// The step sequence: one colour per distinct sequence of steps, with a legend listing the
    /// sequences (`reflect w0 → refract surface`).
    Sequence,
}

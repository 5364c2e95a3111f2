//! The lines under the title: what is drawn of how many entries (a sample? how many have no
//! time?), what colours the rays and what dashes mean; then the marks' key and the stretch.

use std::fmt::Write as _;

use eigenray::{RaySet, Status};

use super::axes::tick_label;
use super::colour::Colouring;
use super::entries::{Drawn, Entries};
use super::layout::Stretch;
use super::marks::ShownReceivers;
use super::markup::{esc, have, thousands};

/// Writes the title in bold and the two caption lines under it: [`drawn_caption`] and
/// [`marks_caption`].
pub(super) fn write_title_and_captions(
    s: &mut String,
    title: &str,
    drawn_line: &str,
    marks_line: &str,
) {
    let _ = writeln!(
        s,
        r##"<text x="12" y="24" font-size="16" font-weight="bold" fill="#222">{}</text>"##,
        esc(title)
    );
    let _ = writeln!(
        s,
        r##"<text x="12" y="44" font-size="12" fill="#555">{}</text>"##,
        esc(drawn_line)
    );
    let _ = writeln!(
        s,
        r##"<text x="12" y="60" font-size="12" fill="#555">{}</text>"##,
        esc(marks_line)
    );
}

/// The first caption line: how many of the `entries` are `drawn`, whether as a sample, how
/// many have no time, what colours them under `colouring` and what their dashes mean.
pub(super) fn drawn_caption(entries: &Entries, drawn: &Drawn, colouring: Colouring) -> String {
    let rays = &drawn.items;
    let mut caption = drawn_count(entries, rays.len());
    let timeless = entries.timeless();
    let without = match entries.rays {
        RaySet::Stationary(_) => "rays have no stationary path",
        _ => "no time",
    };
    let without = |n: usize| match entries.rays {
        RaySet::Stationary(_) if n == 1 => "ray has no stationary path".to_string(),
        RaySet::Stationary(_) => without.to_string(),
        _ => format!("{} {without}", have(n)),
    };
    match (drawn.sampled, timeless) {
        (false, 0) => {}
        (true, 0) => caption.push_str(" (a sample spread over all rays)"),
        (false, n) => {
            let _ = write!(caption, " ({} {})", thousands(n), without(n));
        }
        (true, n) => {
            let _ = write!(
                caption,
                " (a sample spread over all rays; {} {})",
                thousands(n),
                without(n)
            );
        }
    }
    caption.push_str(match colouring {
        Colouring::Time => ", coloured by travel time",
        Colouring::Path => ", coloured by path",
        Colouring::Sequence => ", coloured by step sequence",
    });
    if rays.iter().any(|r| r.status == Status::Obstructed) {
        caption.push_str("; dashed: obstructed");
    }
    if rays.iter().any(|r| r.status == Status::Vertex) {
        caption.push_str("; dotted: vertex (edge-diffracted)");
    }
    caption
}

/// `N of M rays drawn` (or stationary paths, with search arrivals): `drawn` of the entries.
fn drawn_count(entries: &Entries, drawn: usize) -> String {
    match (entries.rays, entries.arrivals.len()) {
        (RaySet::Stationary(st), 0) => format!(
            "{} of {} stationary paths drawn",
            thousands(drawn),
            thousands(st.arrivals())
        ),
        (RaySet::Stationary(st), a) => format!(
            "{} of {} stationary paths and search arrivals drawn",
            thousands(drawn),
            thousands(st.arrivals() + a)
        ),
        (_, 0) => format!(
            "{} of {} rays drawn",
            thousands(drawn),
            thousands(entries.rays_len())
        ),
        (_, a) => format!(
            "{} of {} rays and search arrivals drawn",
            thousands(drawn),
            thousands(entries.rays_len() + a)
        ),
    }
}

/// The second caption line: the marks of sources and receivers, how many receivers are shown
/// when not all, and the `stretch` of an axis.
pub(super) fn marks_caption(receivers: &ShownReceivers, stretch: Option<Stretch>) -> String {
    let mut caption2 = String::from("★ sources, ● receivers");
    if receivers.thinned {
        let _ = write!(
            caption2,
            " ({} of {} receivers shown: those of the drawn rays)",
            thousands(receivers.indices.len()),
            thousands(receivers.total)
        );
    }
    if let Some(Stretch { axis, factor }) = stretch {
        let _ = write!(
            caption2,
            "; {axis} scale stretched ×{}",
            tick_label(factor, factor)
        );
    }
    caption2
}

//! The legend of a picture coloured by path or by step sequence: its lines (each path or
//! sequence drawn, in the scene's words, with its colour and count) and each item's line.

use eigenray::Scene;
use eigenray::scene_parts::{Step, StepKind};

use super::colouring::Colouring;
use super::entries::Item;

/// Height of one line of the path legend.
pub(super) const LEGEND_LINE: f64 = 17.0;
/// At most this many lines of a legend are drawn; a last line counts the rest.
pub(super) const MAX_LEGEND_LINES: usize = 40;

/// The sequence in the scene's words: `reflect w0 → refract surface`, or `direct`.
pub(super) fn sequence_label(scene: &Scene, steps: &[Step]) -> String {
    if steps.is_empty() {
        return "direct".to_string();
    }
    let words: Vec<String> = steps
        .iter()
        .map(|s| {
            let kind = match s.kind {
                StepKind::Reflect => "reflect",
                StepKind::Refract => "refract",
            };
            let name = scene
                .interfaces()
                .get(s.interface)
                .map_or("?", |i| i.name.as_str());
            format!("{kind} {name}")
        })
        .collect();
    words.join(" → ")
}

/// A sequence as a sort key: by number of steps, then step by step (interface, reflect first).
fn sequence_key(steps: &[Step]) -> (usize, Vec<(usize, bool)>) {
    (
        steps.len(),
        steps
            .iter()
            .map(|s| (s.interface, s.kind == StepKind::Refract))
            .collect(),
    )
}

/// One line of a legend.
pub(super) struct LegendEntry {
    /// The path's name or the sequence in words.
    pub(super) label: String,
    /// Its index into [`PATH_COLOURS`](super::colour::PATH_COLOURS) (and
    /// [`path_dash`](super::colour::path_dash)).
    pub(super) colour: usize,
    /// Entries drawn.
    pub(super) count: usize,
}

/// The legend of a colouring and the legend line of each drawn item (none by time).
pub(super) struct Legend {
    /// Its lines, in order.
    pub(super) entries: Vec<LegendEntry>,
    /// The line of each drawn item.
    pub(super) of_item: Vec<usize>,
    /// The legend's heading.
    pub(super) heading: &'static str,
}

impl Legend {
    /// The legend of `items` (drawn in `scene`) under `colouring`; empty by time.
    pub(super) fn new(scene: &Scene, items: &[Item], colouring: Colouring) -> Legend {
        let heading = match colouring {
            Colouring::Time => {
                return Legend {
                    entries: Vec::new(),
                    of_item: Vec::new(),
                    heading: "",
                };
            }
            Colouring::Path => "path (rays drawn)",
            Colouring::Sequence => "sequence (paths drawn)",
        };
        // The groups: paths by index, then search sequences in order of their keys (by path);
        // every sequence in order of its key (by sequence).
        let paths = scene.paths().len();
        let mut sequences: Vec<Vec<Step>> = items
            .iter()
            .filter(|r| colouring == Colouring::Sequence || r.path.is_none())
            .map(|r| r.steps.clone())
            .collect();
        sequences.sort_by_key(|s| sequence_key(s));
        sequences.dedup();
        let sequence_of = |steps: &[Step]| {
            sequences
                .binary_search_by_key(&sequence_key(steps), |s| sequence_key(s))
                .unwrap_or(0)
        };
        // Group of each item: a path index, or `paths` + a sequence's place.
        let group = |r: &Item| match (colouring, r.path) {
            (Colouring::Path, Some(p)) => p,
            _ => paths + sequence_of(&r.steps),
        };
        let mut count = vec![0usize; paths + sequences.len()];
        for r in items {
            count[group(r)] += 1;
        }
        let mut entries = Vec::new();
        let mut line = vec![usize::MAX; count.len()];
        for (g, &c) in count.iter().enumerate() {
            if c == 0 {
                continue;
            }
            let (label, colour) = if g < paths {
                (path_label(scene, g), g)
            } else {
                let k = g - paths;
                let colour = match colouring {
                    Colouring::Sequence => k,
                    _ => paths + k,
                };
                (sequence_label(scene, &sequences[k]), colour)
            };
            line[g] = entries.len();
            entries.push(LegendEntry {
                label,
                colour,
                count: c,
            });
        }
        let of_item = items.iter().map(|r| line[group(r)]).collect();
        Legend {
            entries,
            of_item,
            heading,
        }
    }

    /// Lines drawn: at most [`MAX_LEGEND_LINES`], the last then counting the rest.
    pub(super) fn lines(&self) -> usize {
        self.entries.len().min(MAX_LEGEND_LINES + 1)
    }
}

/// The label of path `p`: its name, or `path p`.
pub(super) fn path_label(scene: &Scene, p: usize) -> String {
    match scene.paths().get(p).and_then(|p| p.name.as_deref()) {
        Some(name) => name.to_string(),
        None => format!("path {p}"),
    }
}

//! The legend of a picture coloured by path or by step sequence: its lines (each path or
//! sequence drawn, in the scene's words, with its colour and count) and each item's line.

use eigenray::Scene;
use eigenray::scene::{Step, StepKind};

use super::colouring::Colouring;
use super::entries::Item;
use super::markup::thousands;

/// Height of one line of the path legend.
pub(super) const LEGEND_LINE: f64 = 17.0;
/// At most this many lines of a legend are drawn; a last line counts the rest.
pub(super) const MAX_LEGEND_LINES: usize = 40;
/// At most this many rows of text hold those lines (a long line wraps onto several rows); the
/// lines that do not fit are counted on the last.
pub(super) const MAX_LEGEND_ROWS: usize = 64;
/// Longest row of a legend line, in characters: a longer line wraps before a `→`.
pub(super) const LEGEND_WRAP: usize = 52;
/// Width of a character of the legend's text (12 px DejaVu Sans, wide ones included), in pixels.
pub(super) const LEGEND_CHAR_W: f64 = 7.4;

/// `text` as rows of at most [`LEGEND_WRAP`] characters, broken before each ` → ` that would
/// overrun (a single step longer than that keeps a row of its own).
pub(super) fn wrap_label(text: &str) -> Vec<String> {
    let mut rows: Vec<String> = Vec::new();
    for (k, part) in text.split(" → ").enumerate() {
        match rows.last_mut() {
            Some(row) if row.chars().count() + 3 + part.chars().count() <= LEGEND_WRAP => {
                row.push_str(" → ");
                row.push_str(part);
            }
            _ if k == 0 => rows.push(part.to_string()),
            _ => rows.push(format!("→ {part}")),
        }
    }
    rows
}

/// The sequence in the scene's words: `reflect w0 → refract surface`, or `direct`; a sequence
/// that repeats a block of steps from its start says so, `(reflect surface → reflect bottom) ×6`
/// (then the steps after the last whole block).
pub(super) fn sequence_label(scene: &Scene, steps: &[Step]) -> String {
    if steps.is_empty() {
        return "direct".to_string();
    }
    let words: Vec<String> = steps
        .iter()
        .map(|s| {
            let kind = s.kind.as_str();
            let name = scene
                .interfaces()
                .get(s.interface)
                .map_or("?", |i| i.name.as_str());
            format!("{kind} {name}")
        })
        .collect();
    repeats_label(&words)
}

/// `words` joined by ` → `, the shortest block that repeats from the start at least twice (and
/// then goes on to the end, a part of it after the last whole one) written once with its count.
fn repeats_label(words: &[String]) -> String {
    let n = words.len();
    for period in 1..=n / 2 {
        if (period..n).all(|i| words[i] == words[i - period]) {
            let block = words[..period].join(" → ");
            let mut label = if period == 1 {
                format!("{block} ×{}", n / period)
            } else {
                format!("({block}) ×{}", n / period)
            };
            for word in &words[n - n % period..] {
                label.push_str(" → ");
                label.push_str(word);
            }
            return label;
        }
    }
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

/// One line of a legend (on one or more rows).
pub(super) struct LegendEntry {
    /// The path's name or the sequence in words.
    pub(super) label: String,
    /// Its index into [`PATH_COLOURS`](super::colour::PATH_COLOURS) (and
    /// [`path_dash`](super::colour::path_dash)).
    pub(super) colour: usize,
    /// Entries drawn.
    pub(super) count: usize,
}

impl LegendEntry {
    /// Its text, `label (count)`, as the rows it is drawn on.
    pub(super) fn rows(&self) -> Vec<String> {
        wrap_label(&format!("{} ({})", self.label, thousands(self.count)))
    }
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

    /// How many of its lines are drawn in full: at most [`MAX_LEGEND_LINES`], on at most
    /// [`MAX_LEGEND_ROWS`] rows with one left for the line that counts the rest.
    pub(super) fn shown(&self) -> usize {
        let mut rows = 0;
        for (k, e) in self.entries.iter().enumerate() {
            let n = e.rows().len();
            let last = k + 1 == self.entries.len();
            let room = if last {
                MAX_LEGEND_ROWS
            } else {
                MAX_LEGEND_ROWS - 1
            };
            if k == MAX_LEGEND_LINES || rows + n > room {
                return k;
            }
            rows += n;
        }
        self.entries.len()
    }

    /// Rows of text drawn: those of the lines shown, and one counting the rest.
    pub(super) fn rows(&self) -> usize {
        let shown = self.shown();
        let rows: usize = self.entries[..shown].iter().map(|e| e.rows().len()).sum();
        rows + usize::from(shown < self.entries.len())
    }

    /// The widest row drawn, in characters.
    pub(super) fn widest_row(&self) -> usize {
        let shown = self.shown();
        let rest = if shown < self.entries.len() {
            let drawn: usize = self.entries[shown..].iter().map(|e| e.count).sum();
            rest_line(self.entries.len() - shown, drawn).chars().count()
        } else {
            0
        };
        self.entries[..shown]
            .iter()
            .flat_map(LegendEntry::rows)
            .map(|r| r.chars().count())
            .max()
            .unwrap_or(0)
            .max(rest)
            .max(self.heading.chars().count())
    }
}

/// The last line of a legend that could not show every line: `… 24 more (24)`.
pub(super) fn rest_line(lines: usize, drawn: usize) -> String {
    format!("… {} more ({})", thousands(lines), thousands(drawn))
}

/// The label of path `p`: its name, or `path p`.
pub(super) fn path_label(scene: &Scene, p: usize) -> String {
    match scene.paths().get(p).and_then(|p| p.name.as_deref()) {
        Some(name) => name.to_string(),
        None => format!("path {p}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_labels_wrap_before_an_arrow() {
        let label = ["reflect surface", "reflect bottom"].repeat(4).join(" → ");
        let rows = wrap_label(&label);
        assert!(rows.len() > 1, "{rows:?}");
        assert!(
            rows.iter().all(|r| r.chars().count() <= LEGEND_WRAP),
            "{rows:?}"
        );
        assert!(rows[1..].iter().all(|r| r.starts_with("→ ")), "{rows:?}");
        assert_eq!(rows.join(" "), label);
        assert_eq!(wrap_label("direct (3)"), ["direct (3)"]);
    }

    #[test]
    fn repeated_blocks_of_steps_are_counted() {
        let words = |list: &[&str]| -> Vec<String> { list.iter().map(|w| w.to_string()).collect() };
        let (s, b) = ("reflect surface", "reflect bottom");
        assert_eq!(
            repeats_label(&words(&[s, b, s, b, s, b])),
            "(reflect surface → reflect bottom) ×3"
        );
        assert_eq!(
            repeats_label(&words(&[s, b, s, b, s])),
            "(reflect surface → reflect bottom) ×2 → reflect surface"
        );
        assert_eq!(repeats_label(&words(&[b, b, b])), "reflect bottom ×3");
        assert_eq!(
            repeats_label(&words(&[s, b, s])),
            "reflect surface → reflect bottom → reflect surface"
        );
        assert_eq!(
            repeats_label(&words(&[s, b, b, s])),
            "reflect surface → reflect bottom → reflect bottom → reflect surface"
        );
    }
}

//! Names from the user in messages: an unknown name with the nearest known one as a
//! suggestion (edit distance), and long names cut to a readable length.

/// The longest name quoted whole in a message, in bytes; a longer one is cut, saying how long
/// it was.
const SHOWN_BYTES: usize = 64;

/// Suggestions are looked for only among names up to this many bytes (the edit distance
/// costs the product of two names' lengths).
const SUGGESTED_BYTES: usize = 256;

/// `name` as a message quotes it: whole up to [`SHOWN_BYTES`], else its start, `…` and its
/// length (`` `aaaa…` (1048576 bytes) ``).
pub(crate) fn shown(name: &str) -> String {
    if name.len() <= SHOWN_BYTES {
        return format!("`{name}`");
    }
    let mut end = SHOWN_BYTES;
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    format!("`{}…` ({} bytes)", &name[..end], name.len())
}

/// The message for an unknown `kind` (`medium`, `interface`) called `name`, with the nearest
/// of `known` when one is near enough to be a typo: `` unknown medium `watr` (did you mean
/// `water`?) ``.
pub(crate) fn unknown<'a>(
    kind: &str,
    name: &str,
    known: impl IntoIterator<Item = &'a str>,
) -> String {
    match nearest(name, known) {
        Some(near) => format!("unknown {kind} {} (did you mean `{near}`?)", shown(name)),
        None => format!("unknown {kind} {}", shown(name)),
    }
}

/// The name of `known` nearest to `name` by edit distance, when that distance is at most a
/// third of the longer name (at least 1, at most 3): a typo, not another name. Ties go to the
/// first.
fn nearest<'a>(name: &str, known: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    if name.len() > SUGGESTED_BYTES {
        return None;
    }
    let name: Vec<char> = name.chars().collect();
    let mut best: Option<(usize, &str)> = None;
    for candidate in known {
        if candidate.len() > SUGGESTED_BYTES {
            continue;
        }
        let other: Vec<char> = candidate.chars().collect();
        let allowed = (name.len().max(other.len()) / 3).clamp(1, 3);
        let d = edit_distance(&name, &other);
        if d <= allowed && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, candidate));
        }
    }
    best.map(|(_, n)| n)
}

/// The Levenshtein distance between `a` and `b`: the fewest insertions, deletions and
/// substitutions of one character that turn one into the other (one row of the table at a
/// time).
fn edit_distance(a: &[char], b: &[char]) -> usize {
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chars(s: &str) -> Vec<char> {
        s.chars().collect()
    }

    #[test]
    fn edit_distances_of_known_pairs() {
        for (a, b, d) in [
            ("", "", 0),
            ("water", "water", 0),
            ("watr", "water", 1),
            ("wtaer", "water", 2),
            ("kitten", "sitting", 3),
            ("", "abc", 3),
            ("flaw", "lawn", 2),
            ("ü", "u", 1),
        ] {
            assert_eq!(edit_distance(&chars(a), &chars(b)), d, "{a} {b}");
            assert_eq!(edit_distance(&chars(b), &chars(a)), d, "{b} {a}");
        }
    }

    #[test]
    fn a_typo_gets_the_nearest_name_and_a_stranger_gets_none() {
        let media = ["air", "sediment", "water"];
        assert_eq!(
            unknown("medium", "watr", media),
            "unknown medium `watr` (did you mean `water`?)"
        );
        assert_eq!(nearest("sedmient", media), Some("sediment"));
        assert_eq!(nearest("aer", media), Some("air"));
        assert_eq!(unknown("medium", "glass", media), "unknown medium `glass`");
        assert_eq!(nearest("x", ["y"]), Some("y"));
        assert_eq!(nearest("xyz", ["abc"]), None);
    }

    #[test]
    fn long_names_are_cut_saying_how_long_they_were() {
        let long = "é".repeat(600_000);
        let text = unknown("interface", &long, ["surface"]);
        assert!(text.len() < 200, "{}", text.len());
        assert!(text.ends_with("(1200000 bytes)"), "{text}");
        assert_eq!(shown("surface"), "`surface`");
    }
}

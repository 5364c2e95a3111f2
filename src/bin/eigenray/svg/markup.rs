//! Writing SVG text: XML escaping, counts in words (`1,234`, `has`/`have`) and text with a
//! white halo.

use std::fmt::Write as _;

/// XML-escapes text for element content and attribute values; characters that XML 1.0 does
/// not allow become spaces (controls) or U+FFFD (U+FFFE, U+FFFF).
pub(super) fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && !matches!(c, '\t' | '\n' | '\r') => out.push(' '),
            '\u{fffe}' | '\u{ffff}' => out.push('\u{fffd}'),
            c => out.push(c),
        }
    }
    out
}

/// `has` for one, `have` for more.
pub(super) fn have(n: usize) -> &'static str {
    if n == 1 { "has" } else { "have" }
}

/// `1234567` as `1,234,567`.
pub fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

/// Text that reads on any background in every renderer: a white outline drawn first, then the
/// text over it (no `paint-order`, which some renderers ignore).
pub(super) fn halo_text(s: &mut String, x: f64, y: f64, attrs: &str, fill: &str, text: &str) {
    let text = esc(text);
    let _ = writeln!(
        s,
        r#"<text x="{x:.2}" y="{y:.2}" {attrs} fill="white" stroke="white" stroke-width="3.5" stroke-linejoin="round">{text}</text><text x="{x:.2}" y="{y:.2}" {attrs} fill="{fill}">{text}</text>"#
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_characters_xml_forbids() {
        assert_eq!(
            esc(r#"a<b & "c">'"#),
            "a&lt;b &amp; &quot;c&quot;&gt;&apos;"
        );
        assert_eq!(esc("a\u{1}b\u{fffe}c\u{ffff}"), "a b\u{fffd}c\u{fffd}");
    }

    #[test]
    fn thousands_separate() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(1_000_000), "1,000,000");
    }
}

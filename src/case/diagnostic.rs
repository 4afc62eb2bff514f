//! Where in a case file a problem is: key paths (`springs[2].stiffness`) to source spans and
//! back, and the rendering of a diagnostic with the offending text (miette).

use miette::{GraphicalReportHandler, GraphicalTheme, NamedSource, SourceSpan};
use std::ops::Range;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// 1-based line and column of a byte offset.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.rfind('\n').map_or(offset, |i| offset - i - 1) + 1;
    (line, column)
}

/// One step of a key path.
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

fn steps(path: &str) -> Vec<Step<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, rest) = part.split_once('[').map_or((part, ""), |(k, r)| (k, r));
        if !key.is_empty() {
            out.push(Step::Key(key));
        }
        for index in rest.split('[') {
            if let Ok(i) = index.trim_end_matches(']').parse() {
                out.push(Step::Index(i));
            }
        }
    }
    out
}

/// The span of the value at `path`, or of the deepest part of the path that exists.
pub fn span_of(text: &str, path: &str) -> Option<Range<usize>> {
    let root = DeTable::parse(text).ok()?;
    let mut span: Option<Range<usize>> = None;
    let mut value: Option<&DeValue> = None;
    let root_table = root.get_ref();
    for step in steps(path) {
        let next: Option<&Spanned<DeValue>> = match (step, value) {
            (Step::Key(k), None) => root_table.get(k),
            (Step::Key(k), Some(DeValue::Table(t))) => t.get(k),
            (Step::Index(i), Some(DeValue::Array(a))) => a.get(i),
            _ => None,
        };
        match next {
            Some(v) => {
                span = Some(v.span());
                value = Some(v.get_ref());
            }
            None => break,
        }
    }
    span
}

/// The key path of the deepest key or value whose span contains `offset`.
pub fn key_at(text: &str, offset: usize) -> Option<String> {
    fn walk(table: &DeTable, prefix: &str, offset: usize, best: &mut Option<String>) {
        for (k, v) in table.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            if (k.span().contains(&offset) || v.span().contains(&offset))
                && best.as_ref().is_none_or(|b| path.len() > b.len())
            {
                *best = Some(path.clone());
            }
            match v.get_ref() {
                DeValue::Table(inner) => walk(inner, &path, offset, best),
                DeValue::Array(items) => {
                    for (i, item) in items.iter().enumerate() {
                        let indexed = format!("{path}[{i}]");
                        if item.span().contains(&offset)
                            && best.as_ref().is_none_or(|b| indexed.len() > b.len())
                        {
                            *best = Some(indexed.clone());
                        }
                        if let DeValue::Table(inner) = item.get_ref() {
                            walk(inner, &indexed, offset, best);
                        }
                    }
                }
                _ => {}
            }
        }
    }
    let root = DeTable::parse(text).ok()?;
    let mut best = None;
    walk(root.get_ref(), "", offset, &mut best);
    best
}

#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{message}")]
struct Rendered {
    message: String,
    #[source_code]
    code: NamedSource<String>,
    #[label("{label}")]
    at: SourceSpan,
    label: String,
    #[help]
    help: Option<String>,
}

/// Render a message with the offending text of `source` underlined (no colour, so the output
/// is the same on a terminal and in a log).
pub fn render(
    name: &str,
    source: &str,
    span: Range<usize>,
    message: &str,
    label: &str,
    help: Option<&str>,
) -> String {
    let end = span.end.min(source.len());
    let start = span.start.min(end);
    let report = Rendered {
        message: message.to_string(),
        code: NamedSource::new(name, source.to_string()),
        at: (start, end - start).into(),
        label: label.to_string(),
        help: help.map(str::to_string),
    };
    let mut out = String::new();
    let handler =
        GraphicalReportHandler::new_themed(GraphicalTheme::unicode_nocolor()).with_width(100);
    if handler.render_report(&mut out, &report).is_err() {
        out = format!("{message}\n");
    }
    out
}

/// ", did you mean `x`?" for the candidate nearest `given` by edit distance, where it is near
/// enough to be a slip (at most a third of its characters differ); empty otherwise.
pub fn did_you_mean<S: AsRef<str>>(given: &str, candidates: &[S]) -> String {
    candidates
        .iter()
        .map(|c| (edit_distance(given, c.as_ref()), c.as_ref()))
        .filter(|(d, c)| *d > 0 && 3 * d <= c.chars().count().max(given.chars().count()))
        .min_by_key(|(d, _)| *d)
        .map_or_else(String::new, |(_, c)| format!(", did you mean `{c}`?"))
}

/// Levenshtein distance between two strings, in characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != *cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

//! The scene reference of `eddy scene-keys` and docs/src/scene-reference.md: one row per key,
//! its type, default and meaning read from the serde structs themselves (through their
//! `schemars` schema, which sees the same attributes and doc comments serde does), its allowed
//! range from the table the validation checks against ([`super::ranges::RANGES`]). The
//! `[refinement]` rows come from the methods' registry (`crate::refine::registry`): each
//! method's parameter struct and the ranges its validation checks.

use serde_json::{Map, Value};

use super::ranges::entry;
use super::{Number, Scene};
use crate::refine::registry;

/// One key of the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyRow {
    /// Dotted path: `[]` is every element of a list, as in `fluid.blocks[].min`.
    pub key: String,
    /// `number`, `[number; 3]`, `table`, ...
    pub kind: String,
    /// The value when left out, or `required`.
    pub default: String,
    /// What the validation allows, and the choices of a named value.
    pub allowed: String,
    /// The first sentence of its doc comment.
    pub meaning: String,
    /// The rest of the doc comment, and what each choice means.
    pub details: String,
}

/// Every key of a scene file, in the order of the structs' fields.
pub fn rows() -> Vec<KeyRow> {
    let mut rows = Walker::rows("", &schemars::schema_for!(Scene));
    rows.extend(refinement_rows());
    rows
}

/// The `[refinement]` keys, from the methods' registry: `method`, each method's own keys (the
/// meaning says which method takes one), then the keys every method shares, once.
fn refinement_rows() -> Vec<KeyRow> {
    let methods = registry::methods();
    let names: Vec<String> = std::iter::once("none")
        .chain(methods.iter().map(|m| m.name))
        .map(|n| format!("\"{n}\""))
        .collect();
    let said: Vec<String> = methods
        .iter()
        .map(|m| format!("\"{}\": {}", m.name, m.summary))
        .collect();
    let mut rows = vec![KeyRow {
        key: "refinement.method".to_owned(),
        kind: "string".to_owned(),
        default: "\"none\"".to_owned(),
        allowed: names.join(" | "),
        meaning: "The SPH turbulence refinement; each method takes only its own keys.".to_owned(),
        details: format!("{}.", said.join("; ")),
    }];
    let mut keys: Vec<(KeyRow, Vec<&str>)> = Vec::new();
    for method in &methods {
        for mut row in Walker::rows("refinement", &method.schema()) {
            let range = method
                .ranges
                .iter()
                .find(|(k, _)| row.key.strip_prefix("refinement.") == Some(k));
            if let Some((_, range)) = range {
                row.allowed = range.describe(false);
            }
            match keys.iter_mut().find(|(r, _)| *r == row) {
                Some((_, by)) => by.push(method.name),
                None => keys.push((row, vec![method.name])),
            }
        }
    }
    keys.sort_by_key(|(_, by)| by.len() == methods.len());
    for (mut row, by) in keys {
        if by.len() < methods.len() {
            let by: Vec<String> = by.iter().map(|n| format!("\"{n}\"")).collect();
            row.meaning = format!("`method = {}`: {}", by.join(" | "), row.meaning);
        }
        rows.push(row);
    }
    rows
}

/// The reference as aligned plain text, one block per top-level key.
pub fn text() -> String {
    let mut out = String::new();
    for (title, rows) in sections(&rows()) {
        let cells: Vec<[&str; 5]> = rows
            .iter()
            .map(|r| [&r.key[..], &r.kind, &r.default, &r.allowed, &r.meaning])
            .collect();
        let widths: Vec<usize> = (0..4)
            .map(|c| {
                cells
                    .iter()
                    .map(|r| r[c].chars().count())
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        out.push_str(&format!("{}\n", title.trim_matches('`')));
        for row in &cells {
            let mut line = String::from("  ");
            for (cell, width) in row.iter().zip(&widths) {
                line.push_str(&format!("{cell:width$}  "));
            }
            line.push_str(row[4]);
            out.push_str(line.trim_end());
            out.push('\n');
        }
        out.push('\n');
    }
    out
}

/// The reference as the book's page (docs/src/scene-reference.md).
pub fn markdown() -> String {
    let mut out = String::from(HEADER);
    for (title, rows) in sections(&rows()) {
        out.push_str(&format!("\n## {title}\n\n"));
        out.push_str("| key | type | default | allowed | meaning |\n|---|---|---|---|---|\n");
        for r in &rows {
            let cells = [
                format!("`{}`", r.key),
                cell(&r.kind),
                cell(&r.default),
                cell(&r.allowed),
                cell(&r.meaning),
            ];
            out.push_str(&format!("| {} |\n", cells.join(" | ")));
        }
        let detailed: Vec<_> = rows.iter().filter(|r| !r.details.is_empty()).collect();
        if !detailed.is_empty() {
            out.push('\n');
        }
        for r in detailed {
            out.push_str(&format!("- `{}`: {}\n", r.key, r.details));
        }
    }
    out
}

const HEADER: &str = "# Scene reference

<!-- Generated by `eddy scene-keys --markdown > docs/src/scene-reference.md`; do not edit. -->

Every key of a scene file, printed by `eddy scene-keys` from the code itself: the type, default
and meaning from the scene's serde structs and their doc comments, the allowed range from the
table the validation checks against. [Scene files](scene-files.md) says how scenes are loaded.

- A key is its dotted path: `time.cfl` is `cfl` in `[time]`. `[]` stands for every element of
  a list: `fluid.blocks[].min` is `min` in each `[[fluid.blocks]]`.
- A key that belongs to one kind of a table starts its meaning with that kind, e.g.
  `type = \"line\"` for `probes[].points`: only line probes take it.
- The default is the value a left-out key takes; `required` keys must be given, and `none`
  means the setting is off (or, for a table, absent).
- Allowed values: a range such as `(0, 1]` or `> 0`, the choices of a named value
  (`\"a\" | \"b\"`), and after `;` a rule that depends on other keys.
";

/// Most choices listed in the allowed column; longer lists go to the details.
const MAX_LISTED: usize = 8;

/// A table cell: `|` escaped, and a dash for nothing.
fn cell(text: &str) -> String {
    if text.is_empty() {
        "-".to_owned()
    } else {
        text.replace('|', "\\|")
    }
}

/// The rows grouped by their top-level table, the top level's own values first.
fn sections(rows: &[KeyRow]) -> Vec<(String, Vec<KeyRow>)> {
    let top = "Top level".to_owned();
    let mut out: Vec<(String, Vec<KeyRow>)> = vec![(top.clone(), Vec::new())];
    for row in rows {
        let head = row.key.split(['.', '[']).next().unwrap_or_default();
        let title = if head == row.key && row.kind != "table" && !row.kind.contains("tables") {
            top.clone()
        } else {
            format!("`{head}`")
        };
        match out.iter_mut().find(|(t, _)| *t == title) {
            Some((_, rows)) => rows.push(row.clone()),
            None => out.push((title, vec![row.clone()])),
        }
    }
    out
}

/// Walks the JSON schema of [`Scene`], resolving `$ref`s against its definitions.
struct Walker {
    defs: Map<String, Value>,
}

impl Walker {
    /// The rows of the keys of the table `schema` describes, under `prefix`.
    fn rows(prefix: &str, schema: &schemars::Schema) -> Vec<KeyRow> {
        let root = schema.as_value();
        let defs = root.get("$defs").and_then(Value::as_object);
        let walker = Walker {
            defs: defs.cloned().unwrap_or_default(),
        };
        let mut rows = Vec::new();
        walker.properties(prefix, root, &mut rows);
        rows
    }

    fn resolve<'a>(&'a self, node: &'a Value) -> &'a Value {
        match node.get("$ref").and_then(Value::as_str) {
            Some(r) => r
                .strip_prefix("#/$defs/")
                .and_then(|name| self.defs.get(name))
                .map_or(node, |def| self.resolve(def)),
            None => node,
        }
    }

    /// The node without an `Option`'s null.
    fn unwrap_option<'a>(&'a self, node: &'a Value) -> &'a Value {
        if let Some(any) = node.get("anyOf").and_then(Value::as_array) {
            if let Some(inner) = any.iter().find(|v| v.get("type") != Some(&"null".into())) {
                return self.resolve(inner);
            }
        }
        self.resolve(node)
    }

    /// A row for each property of the table `node`, under `prefix`.
    fn properties(&self, prefix: &str, node: &Value, out: &mut Vec<KeyRow>) {
        let Some(props) = node.get("properties").and_then(Value::as_object) else {
            return;
        };
        let required = required(node);
        for (name, prop) in props {
            let key = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}.{name}")
            };
            self.key(&key, prop, required.contains(&name.as_str()), out);
        }
    }

    /// The row of one key and those of the keys under it.
    fn key(&self, key: &str, prop: &Value, required: bool, out: &mut Vec<KeyRow>) {
        let node = self.unwrap_option(prop);
        let description = prop
            .get("description")
            .or_else(|| node.get("description"))
            .and_then(Value::as_str)
            .unwrap_or_default();
        let (meaning, mut details) = split_description(description);
        let choices = self.choices(node);
        let default = if required {
            "required".to_owned()
        } else {
            match prop.get("default") {
                Some(Value::Object(_)) => String::new(),
                Some(v) => value(v, &choices),
                None if is_table(node) => String::new(),
                None => "none".to_owned(),
            }
        };
        let mut allowed: Vec<String> = Vec::new();
        let names: Vec<&str> = choices.iter().map(|(v, _)| &v[..]).collect();
        if names.len() > MAX_LISTED {
            allowed.push(format!("one of {} names", names.len()));
            push_sentence(&mut details, &format!("Names: {}", names.join(", ")));
        } else if !names.is_empty() {
            allowed.push(names.join(" | "));
        }
        let said: Vec<String> = choices
            .iter()
            .filter(|(_, d)| !d.is_empty())
            .map(|(v, d)| format!("{v}: {}", d.trim_end_matches('.')))
            .collect();
        push_sentence(&mut details, &said.join("; "));
        if let Some(range) = entry(key) {
            if let Some(r) = range.range {
                allowed.push(r.describe(false));
            }
            allowed.extend(range.rule.map(str::to_owned));
        }
        out.push(KeyRow {
            key: key.to_owned(),
            kind: self.kind(node),
            default,
            allowed: allowed.join("; "),
            meaning,
            details,
        });
        self.below(key, node, out);
    }

    /// The rows of the keys inside `node`: a table's keys, a list of tables' element keys, the
    /// keys of each kind of a tagged table, and the tables an externally tagged choice holds.
    fn below(&self, key: &str, node: &Value, out: &mut Vec<KeyRow>) {
        if node.get("properties").is_some() {
            return self.properties(key, node, out);
        }
        if let Some(items) = node.get("items") {
            let items = self.resolve(items);
            if is_table(items) {
                self.below(&format!("{key}[]"), items, out);
            }
            return;
        }
        let Some(variants) = node.get("oneOf").and_then(Value::as_array) else {
            return;
        };
        let tags: Vec<&str> = variants.iter().filter_map(tag).collect();
        if tags.len() == variants.len() {
            return self.tagged(key, variants, &tags, out);
        }
        // The choices that are tables of keys; the others are listed among the choices.
        let props = variants
            .iter()
            .filter_map(|v| v.get("properties").and_then(Value::as_object));
        for (name, prop) in props.flatten() {
            if is_table(self.resolve(prop)) {
                self.key(&format!("{key}.{name}"), prop, false, out);
            }
        }
    }

    /// A table tagged by its `type`: the tag's row, then each kind's keys, a key several kinds
    /// share once, its meaning saying which kinds take it (all of them: none said).
    fn tagged(&self, key: &str, variants: &[Value], tags: &[&str], out: &mut Vec<KeyRow>) {
        let tag_key = format!("{key}.type");
        let mut allowed: Vec<String> = tags.iter().map(|t| format!("\"{t}\"")).collect();
        allowed = vec![allowed.join(" | ")];
        allowed.extend(entry(&tag_key).and_then(|r| r.rule).map(str::to_owned));
        let described: Vec<String> = variants
            .iter()
            .zip(tags)
            .filter_map(|(v, t)| {
                let d = v.get("description").and_then(Value::as_str)?;
                Some(format!("\"{t}\": {}", one_line(d).trim_end_matches('.')))
            })
            .collect();
        out.push(KeyRow {
            key: tag_key.clone(),
            kind: "string".to_owned(),
            default: "required".to_owned(),
            allowed: allowed.join("; "),
            meaning: "Which kind of table this is; it decides the other keys.".to_owned(),
            details: format!("{}.", described.join("; ")),
        });
        let mut shared: Vec<(KeyRow, Vec<&str>)> = Vec::new();
        for (variant, tag) in variants.iter().zip(tags) {
            let mut rows = Vec::new();
            self.properties(key, variant, &mut rows);
            for row in rows.into_iter().filter(|r| r.key != tag_key) {
                match shared.iter_mut().find(|(r, _)| r.key == row.key) {
                    Some((_, kinds)) => kinds.push(tag),
                    None => shared.push((row, vec![tag])),
                }
            }
        }
        for (mut row, kinds) in shared {
            if kinds.len() < tags.len() {
                let kinds: Vec<String> = kinds.iter().map(|k| format!("\"{k}\"")).collect();
                row.meaning = format!("`type = {}`: {}", kinds.join(" | "), row.meaning);
            }
            out.push(row);
        }
    }

    /// The named values a key takes, with what each means: an enum's strings, or the keys of
    /// an externally tagged choice written `{ name = ... }`.
    fn choices(&self, node: &Value) -> Vec<(String, String)> {
        let node = match node.get("items") {
            Some(items) => self.resolve(items),
            None => node,
        };
        let describe = |v: &Value| {
            v.get("description")
                .and_then(Value::as_str)
                .map(one_line)
                .unwrap_or_default()
        };
        let mut out = Vec::new();
        let strings = |v: &Value, out: &mut Vec<(String, String)>| {
            if let Some(c) = v.get("const").and_then(Value::as_str) {
                out.push((format!("\"{c}\""), describe(v)));
            }
            for c in v
                .get("enum")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                if let Some(c) = c.as_str() {
                    out.push((format!("\"{c}\""), String::new()));
                }
            }
        };
        strings(node, &mut out);
        let variants = node.get("oneOf").and_then(Value::as_array);
        if variants.is_some_and(|vs| vs.iter().any(|v| tag(v).is_some())) {
            return out;
        }
        for v in variants.into_iter().flatten() {
            strings(v, &mut out);
            if let Some(props) = v.get("properties").and_then(Value::as_object) {
                for (name, prop) in props {
                    let inner = self.kind(self.resolve(prop));
                    out.push((format!("{{ {name} = {inner} }}"), describe(v)));
                }
            }
        }
        out
    }

    /// The type in words: `number`, `[number; 3]`, `list of tables`, `string or table`.
    fn kind(&self, node: &Value) -> String {
        let node = self.unwrap_option(node);
        if is_table(node) && node.get("oneOf").is_none() || tag_of_all(node) {
            return "table".to_owned();
        }
        if let Some(items) = node.get("items") {
            let items = self.resolve(items);
            if is_table(items) || tag_of_all(items) {
                return "list of tables".to_owned();
            }
            let inner = self.kind(items);
            return match (node.get("minItems"), node.get("maxItems")) {
                (Some(a), Some(b)) if a == b => format!("[{inner}; {a}]"),
                _ => format!("list of {inner}"),
            };
        }
        if let Some(variants) = node.get("oneOf").and_then(Value::as_array) {
            let tables = variants.iter().any(|v| v.get("properties").is_some());
            return if tables { "string or table" } else { "string" }.to_owned();
        }
        let types: Vec<&str> = match node.get("type") {
            Some(Value::String(t)) => vec![t],
            Some(Value::Array(ts)) => ts.iter().filter_map(Value::as_str).collect(),
            _ => Vec::new(),
        };
        match types.iter().find(|t| **t != "null") {
            Some(&"boolean") => "bool".to_owned(),
            Some(t) => (*t).to_owned(),
            None => "value".to_owned(),
        }
    }
}

/// Whether the node is a table (has keys of its own).
fn is_table(node: &Value) -> bool {
    node.get("properties").is_some() || tag_of_all(node)
}

/// Whether the node is a table tagged by `type` (every variant has a `type` constant).
fn tag_of_all(node: &Value) -> bool {
    node.get("oneOf")
        .and_then(Value::as_array)
        .is_some_and(|vs| vs.iter().all(|v| tag(v).is_some()))
}

/// The `type` constant of a variant of a tagged table.
fn tag(variant: &Value) -> Option<&str> {
    variant.pointer("/properties/type/const")?.as_str()
}

fn required(node: &Value) -> Vec<&str> {
    let list = node.get("required").and_then(Value::as_array);
    list.into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect()
}

/// A default as a scene file writes it; `all` for a list of every choice.
fn value(v: &Value, choices: &[(String, String)]) -> String {
    match v {
        Value::Null => "none".to_owned(),
        Value::Number(n) => n.as_f64().map_or(n.to_string(), |x| Number(x).to_string()),
        Value::String(s) => format!("\"{s}\""),
        Value::Array(items) => {
            let items: Vec<String> = items.iter().map(|i| value(i, &[])).collect();
            let all = choices.iter().filter(|(c, _)| c.starts_with('"')).count();
            if items.len() > 3 && items.len() == all {
                "all".to_owned()
            } else {
                format!("[{}]", items.join(", "))
            }
        }
        other => other.to_string(),
    }
}

/// A doc comment on one line, its rustdoc links (``[`Type`]``) plain code.
fn one_line(text: &str) -> String {
    let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut out = String::with_capacity(text.len());
    let mut rest = &text[..];
    while let Some(start) = rest.find("[`") {
        let link = rest[start + 1..]
            .find("`]")
            .map(|end| start + 1 + end + 2)
            .filter(|&end| !rest[end..].starts_with('('));
        let Some(end) = link else {
            out.push_str(&rest[..start + 2]);
            rest = &rest[start + 2..];
            continue;
        };
        out.push_str(&rest[..start]);
        out.push_str(&rest[start + 1..end - 1]);
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// The first sentence of a doc comment, and the rest: a sentence ends at a full stop before a
/// capital, unless the word before it is an abbreviation (`et al.`, `Eq.`, `Sec.`).
fn split_description(text: &str) -> (String, String) {
    let text = one_line(text);
    let bytes = text.as_bytes();
    for (i, _) in text.match_indices(". ") {
        let next = bytes.get(i + 2).copied().unwrap_or(b' ');
        let word = text[..i].rsplit(' ').next().unwrap_or_default();
        let abbreviation = ["al", "Eq", "Sec", "Fig", "e.g", "i.e", "cf"].contains(&word);
        if (next.is_ascii_uppercase() || next == b'`') && !abbreviation {
            return (text[..=i].to_owned(), text[i + 2..].to_owned());
        }
    }
    (text, String::new())
}

/// Appends a sentence to `text`.
fn push_sentence(text: &mut String, sentence: &str) {
    if sentence.is_empty() {
        return;
    }
    if !text.is_empty() {
        text.push(' ');
    }
    text.push_str(sentence);
    if !sentence.ends_with('.') {
        text.push('.');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_first_sentence_ends_at_a_full_stop_before_a_capital() {
        let (first, rest) = split_description("Wang et al. Sec. 5 says so, m. The rest.");
        assert_eq!(first, "Wang et al. Sec. 5 says so, m.");
        assert_eq!(rest, "The rest.");
    }

    #[test]
    fn rustdoc_links_become_plain_code_and_web_links_stay() {
        assert_eq!(
            one_line("see [`Grid`] and\n [`a`](b), [x]"),
            "see `Grid` and [`a`](b), [x]"
        );
    }
}

//! Reading scene files, with errors that name the file, line, column and field.

use std::path::{Path, PathBuf};

use ron::extensions::Extensions;

use super::format::Scene;
use super::validate::validate;

/// Why a scene cannot be used. Every variant names where the problem is.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene {path}: {source}")]
    Io {
        /// The scene file.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The file is not valid RON for a scene (syntax, unknown field or variant, wrong type).
    #[error("{path}:{line}:{column}: {message}")]
    Parse {
        /// The scene file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser says.
        message: String,
    },
    /// A value is well-formed but physically or logically invalid.
    #[error("{}`{field}`: {message}", .location.as_ref().map(|l| format!("{l}: ")).unwrap_or_default())]
    Invalid {
        /// Where the field is, once known.
        location: Option<Location>,
        /// Path of the field, like `cloths[0].material.density`.
        field: String,
        /// What is wrong and what to do.
        message: String,
    },
}

/// A place in a scene file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The scene file.
    pub path: String,
    /// 1-based line and column of the field, when it is written out in the file (a
    /// defaulted field has none).
    pub line_column: Option<(usize, usize)>,
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line_column {
            Some((line, column)) => write!(f, "{}:{line}:{column}", self.path),
            None => write!(f, "{}", self.path),
        }
    }
}

impl SceneError {
    /// An invalid value at `field`.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        SceneError::Invalid { location: None, field: field.into(), message: message.into() }
    }

    /// Attaches the file, and the line and column of the field in `text`, to an
    /// [`SceneError::Invalid`] that has none yet.
    pub fn located(self, path: &Path, text: &str) -> Self {
        match self {
            SceneError::Invalid { location: None, field, message } => SceneError::Invalid {
                location: Some(Location { path: path.display().to_string(), line_column: locate_field(text, &field) }),
                field,
                message,
            },
            other => other,
        }
    }
}

/// A scene read from a file, with the text its error messages point into.
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// The parsed and validated scene.
    pub scene: Scene,
    /// Where it was read from.
    pub path: PathBuf,
    /// The file's text.
    pub text: String,
}

impl SceneFile {
    /// The folder relative paths in the scene (meshes) are resolved against.
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }
}

/// RON extensions scenes are read and written with: optional values without `Some(…)`,
/// and enum variants holding a struct written as `Variant(field: …)`.
const SCENE_EXTENSIONS: Extensions = Extensions::IMPLICIT_SOME.union(Extensions::UNWRAP_VARIANT_NEWTYPES);

/// Reads, parses and validates the scene at `path`.
pub fn load_scene(path: &Path) -> Result<SceneFile, SceneError> {
    let text =
        std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.display().to_string(), source })?;
    let scene = parse_scene(&text, path)?;
    Ok(SceneFile { scene, path: path.to_owned(), text })
}

/// Parses and validates scene text; `path` is only used in messages.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let options = ron::Options::default().with_default_extension(SCENE_EXTENSIONS);
    let scene: Scene = options.from_str(text).map_err(|e| SceneError::Parse {
        path: path.display().to_string(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    })?;
    validate(&scene).map_err(|e| e.located(path, text))?;
    Ok(scene)
}

/// Writes a scene as pretty RON that [`parse_scene`] reads back to the same scene.
pub fn scene_to_ron(scene: &Scene) -> String {
    let config = ron::ser::PrettyConfig::default().struct_names(true).extensions(SCENE_EXTENSIONS);
    ron::ser::to_string_pretty(scene, config).expect("a scene is always serialisable")
}

/// Finds the 1-based line and column of `field` (like `cloths[1].material.density`) in
/// RON text, by walking the text's nesting. `None` when the field is not written out.
pub fn locate_field(text: &str, field: &str) -> Option<(usize, usize)> {
    let tokens = tokenize(text);
    let mut at = 0;
    let mut found = None;
    for segment in field_segments(field) {
        let (open, close) = enter_container(&tokens, at)?;
        at = match segment {
            Segment::Name(name) => {
                let ident = item_starts(&tokens, open, close)
                    .into_iter()
                    .find(|&i| tokens[i].text == name && tokens.get(i + 1).is_some_and(|t| t.text == ":"))?;
                found = Some(ident);
                ident + 2
            }
            Segment::Index(n) => {
                let item = *item_starts(&tokens, open, close).get(n)?;
                found = Some(item);
                item
            }
        };
    }
    found.map(|i| (tokens[i].line, tokens[i].column))
}

enum Segment<'a> {
    Name(&'a str),
    Index(usize),
}

fn field_segments(field: &str) -> Vec<Segment<'_>> {
    let mut segments = Vec::new();
    for part in field.split('.') {
        let (name, indices) = part.split_once('[').map_or((part, ""), |(n, rest)| (n, rest));
        if !name.is_empty() {
            segments.push(Segment::Name(name));
        }
        for index in indices.split('[') {
            if let Ok(n) = index.trim_end_matches(']').parse() {
                segments.push(Segment::Index(n));
            }
        }
    }
    segments
}

struct Token<'a> {
    text: &'a str,
    line: usize,
    column: usize,
}

/// Splits RON into identifiers, literals and punctuation, dropping blanks and comments.
fn tokenize(text: &str) -> Vec<Token<'_>> {
    let mut tokens = Vec::new();
    let bytes = text.as_bytes();
    let (mut i, mut line, mut line_start) = (0, 1, 0);
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        let column = text[line_start..i].chars().count() + 1;
        if c == b'\n' {
            line += 1;
            line_start = i + 1;
            i += 1;
            continue;
        } else if c.is_ascii_whitespace() {
            i += 1;
            continue;
        } else if text[i..].starts_with("//") {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        } else if text[i..].starts_with("/*") {
            let end = text[i + 2..].find("*/").map_or(bytes.len(), |e| i + 2 + e + 2);
            for (k, b) in bytes[i..end].iter().enumerate() {
                if *b == b'\n' {
                    line += 1;
                    line_start = i + k + 1;
                }
            }
            i = end;
            continue;
        } else if c == b'"' {
            i += 1;
            while i < bytes.len() && bytes[i] != b'"' {
                i += if bytes[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(bytes.len());
        } else if b"()[]{}:,".contains(&c) {
            i += 1;
        } else {
            while i < bytes.len() && !bytes[i].is_ascii_whitespace() && !b"()[]{}:,\"".contains(&bytes[i]) {
                i += 1;
            }
        }
        tokens.push(Token { text: &text[start..i], line, column });
    }
    tokens
}

/// Skips a struct or variant name (and an explicit `Some(`) at `at` and returns the
/// indices of the opening and closing brackets of the container that follows.
fn enter_container(tokens: &[Token<'_>], mut at: usize) -> Option<(usize, usize)> {
    let is_open = |k: usize| tokens.get(k).is_some_and(|t| matches!(t.text, "(" | "[" | "{"));
    if tokens.get(at)?.text == "Some" && is_open(at + 1) {
        at += 2;
    }
    if !is_open(at) {
        let named = !matches!(tokens.get(at)?.text, ")" | "]" | "}" | ":" | ",");
        if !(named && is_open(at + 1)) {
            return None;
        }
        at += 1;
    }
    let mut depth = 0;
    for (k, token) in tokens.iter().enumerate().skip(at) {
        match token.text {
            "(" | "[" | "{" => depth += 1,
            ")" | "]" | "}" => {
                depth -= 1;
                if depth == 0 {
                    return Some((at, k));
                }
            }
            _ => {}
        }
    }
    None
}

/// Token indices where each comma-separated item of the container `(open, close)` starts.
fn item_starts(tokens: &[Token<'_>], open: usize, close: usize) -> Vec<usize> {
    let mut starts = Vec::new();
    let mut depth = 0;
    let mut expecting = true;
    for (k, token) in tokens.iter().enumerate().take(close).skip(open + 1) {
        if depth == 0 && expecting && token.text != "," {
            starts.push(k);
            expecting = false;
        }
        match token.text {
            "(" | "[" | "{" => depth += 1,
            ")" | "]" | "}" => depth -= 1,
            "," if depth == 0 => expecting = true,
            _ => {}
        }
    }
    starts
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "Scene(\n  name: \"a\", // the name\n  cloths: [\n    (name: \"x\", material: (density: 1)),\n    (\n      name: \"y\",\n      material: (density: -1),\n    ),\n  ],\n)\n";

    #[test]
    fn fields_are_found_through_structs_and_lists() {
        assert_eq!(locate_field(TEXT, "name"), Some((2, 3)));
        assert_eq!(locate_field(TEXT, "cloths[1].material.density"), Some((7, 18)));
        assert_eq!(locate_field(TEXT, "cloths[0].material"), Some((4, 17)));
        assert_eq!(locate_field(TEXT, "cloths[1]"), Some((5, 5)));
        assert_eq!(locate_field(TEXT, "cloths[2]"), None);
        assert_eq!(locate_field(TEXT, "gravity"), None);
    }
}

//! `--set key=value`: one key of a scene changed before the scene is read, as Mitsuba's
//! `-D` does.
//!
//! A [`Setting`] names a key by its dotted path (`camera.fov`, `lights[0].color`,
//! `materials.red.kd`, `output.encoding`) and gives a TOML value (`30`, `[1, 0, 0]`,
//! `true`; a word that is not TOML, such as `srgb`, is a string). [`apply`] writes the
//! settings into the scene's text and keeps a map from the new text's lines to the file's,
//! so that every error and warning still names the file's own line, and an error in a set
//! value names the `--set` argument.
//!
//! Rules: an existing key's value is replaced in place (a value over several lines leaves
//! as many blank lines, so no line moves); a new key goes on the line after its table's
//! header (`[camera]`, `[[lights]]`), inside the braces of an inline table, or at the top
//! of the file for a top-level key; a table that does not exist (`[output]`) is appended
//! at the end. An index past the end of an array, a path through a value that is not a
//! table, and a table written only with dotted keys are errors naming the argument.

use std::fmt;
use std::str::FromStr;

use toml::de::{DeArray, DeTable, DeValue};

/// One step of a key's path.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Step {
    /// A table's key.
    Key(String),
    /// An element of an array of tables.
    Index(usize),
}

/// One `key=value` change of a scene ([`crate::scene::LoadOptions::settings`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Setting {
    /// The argument as given, for messages.
    arg: String,
    /// The path, never empty, ending with a [`Step::Key`].
    path: Vec<Step>,
    /// The value as one line of TOML.
    value: String,
}

/// Why a setting cannot be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("--set {arg}: {message}")]
pub struct SetError {
    /// The argument as given.
    pub arg: String,
    /// What is wrong with it.
    pub message: String,
}

impl Setting {
    /// The key's path as scene errors name keys (`lights[0].color`).
    pub fn key(&self) -> String {
        path_key(&self.path)
    }

    /// The value as it is written into the scene (TOML).
    pub fn value(&self) -> &str {
        &self.value
    }

    fn error(&self, message: impl Into<String>) -> SetError {
        SetError {
            arg: self.arg.clone(),
            message: message.into(),
        }
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.arg)
    }
}

impl FromStr for Setting {
    type Err = SetError;

    /// Parses `key=value`: a dotted path of bare keys (letters, digits, `_`, `-`), each
    /// optionally followed by `[N]`, then `=`, then a TOML value on one line, or a word
    /// taken as a string.
    fn from_str(arg: &str) -> Result<Setting, SetError> {
        let fail = |message: &str| SetError {
            arg: arg.to_owned(),
            message: message.to_owned(),
        };
        let (key, value) = arg
            .split_once('=')
            .ok_or_else(|| fail("expected key=value, e.g. camera.fov=30"))?;
        let (key, value) = (key.trim(), value.trim());
        if value.is_empty() {
            return Err(fail("the value is empty"));
        }
        if value.contains(['\n', '\r']) {
            return Err(fail("the value must be one line"));
        }
        let mut path = Vec::new();
        for part in key.split('.') {
            let (name, mut rest) = match part.find('[') {
                Some(i) => (&part[..i], &part[i..]),
                None => (part, ""),
            };
            let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
            if name.is_empty() || !name.chars().all(bare) {
                return Err(fail(
                    "the key must be a dotted path of bare TOML keys, each with an optional [N]",
                ));
            }
            path.push(Step::Key(name.to_owned()));
            while !rest.is_empty() {
                let close = rest
                    .find(']')
                    .ok_or_else(|| fail("an index needs its closing ]"))?;
                let n: usize = rest[1..close]
                    .parse()
                    .map_err(|_| fail("an index must be a whole number, e.g. lights[0]"))?;
                path.push(Step::Index(n));
                rest = &rest[close + 1..];
                if !rest.is_empty() && !rest.starts_with('[') {
                    return Err(fail("an index ends a path step: write lights[0].color"));
                }
            }
        }
        if !matches!(path.last(), Some(Step::Key(_))) {
            return Err(fail("the path must end with a key, not an index"));
        }
        let value = if DeValue::parse(value).is_ok() {
            value.to_owned()
        } else {
            let escaped = value.replace('\\', "\\\\").replace('"', "\\\"");
            format!("\"{escaped}\"")
        };
        Ok(Setting {
            arg: arg.to_owned(),
            path,
            value,
        })
    }
}

/// A path as scene errors name keys (`lights[0].color`).
fn path_key(path: &[Step]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// Where a line of the text with settings came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Origin {
    /// This line of the file (1-based).
    File(usize),
    /// Written by settings[.0]; .1 is the file's line it replaces or follows.
    Set(usize, usize),
}

/// A scene's text with its settings made, and the way back to the file's lines.
#[derive(Clone, Debug)]
pub struct Applied {
    /// The text to parse.
    pub text: String,
    origins: Vec<Origin>,
    keys: Vec<(String, String)>,
}

impl Applied {
    /// The file's line for line `line` (1-based) of [`Applied::text`].
    pub fn file_line(&self, line: usize) -> usize {
        match self.origins.get(line.wrapping_sub(1)) {
            Some(Origin::File(l)) | Some(Origin::Set(_, l)) => *l,
            None => line,
        }
    }

    /// The `--set` argument that wrote line `line` of [`Applied::text`], when one did and
    /// it set `key`.
    pub fn setting_for(&self, line: usize, key: &str) -> Option<&str> {
        match self.origins.get(line.wrapping_sub(1)) {
            Some(Origin::Set(i, _)) if self.keys[*i].0 == key => Some(&self.keys[*i].1),
            _ => None,
        }
    }

    /// `file:LINE:...` with LINE read as a line of [`Applied::text`], rewritten to the
    /// file's line; other text is returned as it is.
    pub fn remap_located(&self, s: &str, file: &str) -> String {
        let Some(rest) = s.strip_prefix(file).and_then(|r| r.strip_prefix(':')) else {
            return s.to_owned();
        };
        let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        match rest[..digits].parse::<usize>() {
            Ok(line) => format!("{file}:{}{}", self.file_line(line), &rest[digits..]),
            Err(_) => s.to_owned(),
        }
    }
}

/// `src` with every setting made, in order (a later one sees the earlier ones).
pub fn apply(src: &str, settings: &[Setting]) -> Result<Applied, SetError> {
    let mut applied = Applied {
        text: src.to_owned(),
        origins: (1..=src.lines().count().max(1)).map(Origin::File).collect(),
        keys: settings.iter().map(|s| (s.key(), s.arg.clone())).collect(),
    };
    for (i, s) in settings.iter().enumerate() {
        apply_one(&mut applied, i, s)?;
    }
    Ok(applied)
}

/// The 0-based line of byte `pos`.
fn line_index(text: &str, pos: usize) -> usize {
    text.as_bytes()[..pos.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

fn apply_one(applied: &mut Applied, index: usize, s: &Setting) -> Result<(), SetError> {
    // A text that is not TOML is left for the scene's parser to report.
    let Ok(root) = DeTable::parse(&applied.text) else {
        return Ok(());
    };
    let text = applied.text.clone();
    let (key, parents) = match s.path.split_last() {
        Some((Step::Key(k), parents)) => (k.as_str(), parents),
        _ => unreachable!("a setting's path ends with a key"),
    };
    // Walk to the table that holds the key: its span and contents.
    let mut table: &DeTable<'_> = root.get_ref();
    let mut span: Option<std::ops::Range<usize>> = None;
    // The array of tables a key step found, for the index step after it.
    let mut array: Option<&DeArray<'_>> = None;
    for (n, step) in parents.iter().enumerate() {
        let here = path_key(&parents[..=n]);
        match step {
            Step::Key(k) => match table.get(k.as_str()) {
                Some(v) => match v.get_ref() {
                    DeValue::Table(t) => {
                        table = t;
                        span = Some(v.span());
                    }
                    DeValue::Array(items)
                        if items
                            .iter()
                            .all(|i| matches!(i.get_ref(), DeValue::Table(_))) =>
                    {
                        if !matches!(parents.get(n + 1), Some(Step::Index(_))) {
                            return Err(s.error(format!(
                                "{here} is an array: give an index, e.g. {here}[0]"
                            )));
                        }
                        array = Some(items);
                        span = Some(v.span());
                    }
                    _ => return Err(s.error(format!("{here} is not a table"))),
                },
                None => {
                    if parents[n..].iter().any(|p| matches!(p, Step::Index(_))) {
                        return Err(s.error(format!("the scene has no {here}")));
                    }
                    return append_table(applied, index, s, parents, key);
                }
            },
            Step::Index(i) => {
                let Step::Key(name) = &parents[n - 1] else {
                    unreachable!("an index follows a key")
                };
                let Some(items) = array.take() else {
                    return Err(s.error(format!("{name} is not an array")));
                };
                let Some(item) = items.get(*i) else {
                    let n = items.len();
                    return Err(s.error(match n {
                        0 => format!("{name} is empty, so there is no {here}"),
                        1 => format!("{name} has 1 entry ({name}[0]), so there is no {here}"),
                        _ => format!(
                            "{name} has {n} entries ({name}[0] to {name}[{}]), so there is no {here}",
                            n - 1
                        ),
                    }));
                };
                let DeValue::Table(t) = item.get_ref() else {
                    return Err(s.error(format!("{here} is not a table")));
                };
                table = t;
                span = Some(item.span());
            }
        }
    }
    if let Some(v) = table.get(key) {
        // Replace the value in place, keeping the file's line count.
        let r = v.span();
        let (first, last) = (line_index(&text, r.start), line_index(&text, r.end));
        let mut new = String::with_capacity(text.len() + s.value.len());
        new.push_str(&text[..r.start]);
        new.push_str(&s.value);
        new.extend(std::iter::repeat_n('\n', last - first));
        new.push_str(&text[r.end..]);
        let file_line = applied.file_line(first + 1);
        if let Some(o) = applied.origins.get_mut(first) {
            *o = Origin::Set(index, file_line);
        }
        applied.text = new;
        return Ok(());
    }
    let line = format!("{key} = {}", s.value);
    match span {
        None => insert_line(applied, index, 0, &line),
        Some(r) => match text.as_bytes().get(r.start) {
            Some(b'[') if own_header(&text[r.start..], parents) => {
                let header = line_index(&text, r.start);
                insert_line(applied, index, header + 1, &line)
            }
            Some(b'{') => {
                let open = r.start + 1;
                let empty = text[open..].trim_start().starts_with('}');
                let item = if empty {
                    format!(" {line} ")
                } else {
                    format!(" {line},")
                };
                let l = line_index(&text, open);
                applied.text = format!("{}{item}{}", &text[..open], &text[open..]);
                let file_line = applied.file_line(l + 1);
                applied.origins[l] = Origin::Set(index, file_line);
                Ok(())
            }
            _ => {
                let table = path_key(parents);
                Err(s.error(format!(
                    "{table} has no header of its own ([{table}]: it is written with dotted \
                     keys or only through tables inside it); add one, or set a key it has"
                )))
            }
        },
    }
}

/// Whether `text` starts with the header of the table at `parents` (`[camera]`,
/// `[[lights]]` for `lights[1]`), not with a header of a table inside it.
fn own_header(text: &str, parents: &[Step]) -> bool {
    let line = text.lines().next().unwrap_or("");
    let name: String = line
        .trim_start_matches('[')
        .split(']')
        .next()
        .unwrap_or("")
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    let keys: Vec<&str> = parents
        .iter()
        .filter_map(|p| match p {
            Step::Key(k) => Some(k.as_str()),
            Step::Index(_) => None,
        })
        .collect();
    name == keys.join(".")
}

/// Writes `line` as line `at` (0-based) of the text, moving the rest down.
fn insert_line(applied: &mut Applied, index: usize, at: usize, line: &str) -> Result<(), SetError> {
    let text = &applied.text;
    let mut pos = 0;
    for _ in 0..at {
        match text[pos..].find('\n') {
            Some(i) => pos += i + 1,
            None => {
                pos = text.len();
                break;
            }
        }
    }
    let sep = if pos == text.len() && !text.is_empty() && !text.ends_with('\n') {
        "\n"
    } else {
        ""
    };
    let follows = if at == 0 { 1 } else { applied.file_line(at) };
    applied.text = format!("{}{sep}{line}\n{}", &text[..pos], &text[pos..]);
    let at = at.min(applied.origins.len());
    applied.origins.insert(at, Origin::Set(index, follows));
    Ok(())
}

/// Appends `[a.b]` with `key = value` at the end of the text, for a table the scene does
/// not have.
fn append_table(
    applied: &mut Applied,
    index: usize,
    s: &Setting,
    parents: &[Step],
    key: &str,
) -> Result<(), SetError> {
    let header = path_key(parents);
    let last = applied.origins.len();
    let sep = if applied.text.is_empty() || applied.text.ends_with('\n') {
        ""
    } else {
        "\n"
    };
    applied
        .text
        .push_str(&format!("{sep}[{header}]\n{key} = {}\n", s.value));
    applied.origins.push(Origin::Set(index, last));
    applied.origins.push(Origin::Set(index, last));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(src: &str, args: &[&str]) -> Result<Applied, SetError> {
        let settings: Vec<Setting> = args.iter().map(|a| a.parse().unwrap()).collect();
        apply(src, &settings)
    }

    const SCENE: &str = "ambient = [0.2, 0.2, 0.2]\n\n[camera]\neye = [0, 0, 5]\nfov = 45\n\n[[lights]]\nposition = [1, 1, 1]\ncolor = [1,\n  1, 1]\n\n[[lights]]\nposition = [2, 2, 2]\ncolor = { r = 1 }\n";

    #[test]
    fn replaces_in_place_without_moving_lines() {
        let a = set(SCENE, &["camera.fov=30", "lights[0].color=[1,0,0]"]).unwrap();
        assert!(a.text.contains("fov = 30\n"), "{}", a.text);
        assert!(a.text.contains("color = [1,0,0]\n\n"), "{}", a.text);
        assert_eq!(a.text.lines().count(), SCENE.lines().count());
        assert_eq!(a.setting_for(5, "camera.fov"), Some("camera.fov=30"));
        assert_eq!(a.setting_for(5, "camera.eye"), None);
        assert_eq!(a.file_line(12), 12);
    }

    #[test]
    fn new_keys_go_after_the_header_and_lines_map_back() {
        let a = set(
            SCENE,
            &["camera.samples=2", "shadows=true", "lights[1].kind=spot"],
        )
        .unwrap();
        let lines: Vec<&str> = a.text.lines().collect();
        assert_eq!(lines[0], "shadows = true");
        assert_eq!(lines[4], "samples = 2");
        assert!(
            a.text
                .contains("[[lights]]\nkind = \"spot\"\nposition = [2, 2, 2]")
        );
        // The file's line 5 (fov) is line 7 now.
        assert_eq!(lines[6], "fov = 45");
        assert_eq!(a.file_line(7), 5);
        assert_eq!(a.setting_for(1, "shadows"), Some("shadows=true"));
        assert_eq!(
            a.remap_located("s.toml:7: camera.fov: bad", "s.toml"),
            "s.toml:5: camera.fov: bad"
        );
        toml::de::DeTable::parse(&a.text).unwrap();
    }

    #[test]
    fn missing_tables_are_appended_and_inline_tables_filled() {
        let a = set(SCENE, &["output.encoding=srgb", "lights[1].color.g=0.5"]).unwrap();
        assert!(
            a.text.ends_with("[output]\nencoding = \"srgb\"\n"),
            "{}",
            a.text
        );
        assert!(a.text.contains("color = { g = 0.5, r = 1 }"), "{}", a.text);
        toml::de::DeTable::parse(&a.text).unwrap();
    }

    #[test]
    fn bad_paths_and_arguments_are_errors_naming_the_argument() {
        let e = set(SCENE, &["lights[2].color=[1,1,1]"]).unwrap_err();
        assert_eq!(e.arg, "lights[2].color=[1,1,1]");
        assert!(e.message.contains("lights has 2 entries"), "{e}");
        assert!(
            set(SCENE, &["ambient.x=1"])
                .unwrap_err()
                .message
                .contains("not a table")
        );
        assert!(
            set(SCENE, &["lights.color=1"])
                .unwrap_err()
                .message
                .contains("give an index")
        );
        for bad in [
            "fov",
            "camera.fov=",
            "camera..fov=1",
            "lights[x].color=1",
            "lights[0]=1",
            "a b=1",
        ] {
            assert!(bad.parse::<Setting>().is_err(), "{bad}");
        }
        let e = set("a.b = 1\n", &["a.c=2"]).unwrap_err();
        assert!(e.message.contains("no header of its own"), "{e}");
        let e = set("[m.red]\nka = 1\n", &["m.x=2"]).unwrap_err();
        assert!(e.message.contains("no header of its own"), "{e}");
    }

    #[test]
    fn words_are_strings_and_toml_is_toml() {
        let s: Setting = "output.encoding=srgb".parse().unwrap();
        assert_eq!(s.value(), "\"srgb\"");
        let s: Setting = "x=say \"hi\"".parse().unwrap();
        assert_eq!(s.value(), "\"say \\\"hi\\\"\"");
        let s: Setting = "camera.fov = 1e3".parse().unwrap();
        assert_eq!((s.key(), s.value()), ("camera.fov".to_owned(), "1e3"));
    }
}

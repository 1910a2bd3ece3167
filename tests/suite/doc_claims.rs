//! The docs' claims about the tree exist in it (issue 44, item 6). README.md and docs/**/*.md
//! cite repository files (`crates/integrator/src/render.rs`, `scenes/x.toml`), code items in
//! backticks (`Renderer::new`, `estimate_memory`, `DEFAULT_CACHE_BINS`), `bdpm` flags,
//! examples and benches (`-p bdpm-mis --example two_estimates`), links with anchors
//! (`results.md#current-defaults`) and sections by title (`docs/results.md, "Title"`); this
//! test finds each and checks it against the tree, so a rename or a move that the docs did not
//! follow fails here.
//!
//! What is read: README.md and docs/**/*.md, except docs/results/ (raw reports the tools wrote,
//! with their own commands and paths) and, for everything but links, docs/notebook/: the lab
//! notebook is a dated record, moved there verbatim, that names scratch builds, removed
//! functions and files as they were when it was written; its links must still resolve, its
//! prose is history. Section titles cited from code comments, scripts and scene files
//! (`// docs/results.md, "Title"`) are checked too, since moving a section breaks them.
//!
//! How an item is found: the `.rs` files under crates/, tests/ and benches/ are lexed (comments
//! and string contents apart) and their definitions indexed: `fn`, `struct`, `enum`, `trait`,
//! `type`, `const`, `static`, `mod`, `macro_rules!`, enum variants, struct fields, with the type
//! or trait that owns each method, associated item, variant and field (`impl X`, `impl T for X`,
//! derives of `Default`). `A::b` needs `b` owned by `A`; a lone `snake_case` name may be any
//! definition or a string literal (report keys, EXR layer names); a lone lowercase word without
//! `_` is not checked (mode names, stage names and plain words look the same).

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::fs;
use std::path::Path;

/// Top-level entries of the repository that a cited path starts with.
const ROOTS: [&str; 6] = [
    "crates/", "tests/", "scripts/", "scenes/", "docs/", "benches/",
];

/// Names in backticks that are not this repository's items but look like them, each
/// defined elsewhere: std's and serde's traits and types that the docs say our types implement
/// or use, the external crates (and primitive types) whose paths they cite, and the std
/// methods docs/performance.md's profile names.
const EXTERNAL: [&str; 19] = [
    "Serialize",
    "Deserialize",
    "FromStr",
    "Default",
    "Debug",
    "Ok",
    "Cow",
    "Vec4",
    "sin_cos",
    "call_mut",
    "f32",
    "std",
    "core",
    "glam",
    "obvhs",
    "rayon",
    "serde",
    "clap",
    "exr",
];

/// SeeSharp's names (the `camis` paper's code), which docs/method-notes.md sets beside ours.
const SEESHARP: [&str; 3] = ["CorrelAwareRatios", "MergeMis", "PdfFromAncestor"];

/// Items that docs/performance.md records as removed by a change ("`Photon::vertex` is gone").
const REMOVED: [&str; 2] = ["Photon::vertex", "Photon::position"];

/// Flags of other tools that the docs show on their own (`--no-default-features`), which the
/// check would otherwise read as `bdpm`'s: cargo's, the test harness's, valgrind's, divan's
/// and Slurm's `sbatch`.
const FOREIGN_FLAGS: [&str; 6] = [
    "no-default-features",
    "nocapture",
    "cachegrind-out-file",
    "dump-instr",
    "sample-count",
    "dependency",
];

/// The definitions of the source files, by name and by owner.
#[derive(Default)]
struct Items {
    /// Every defined name (items, variants, fields, macros).
    defs: HashSet<String>,
    /// Names of structs, enums, traits, unions, type aliases and enum variants.
    types: HashSet<String>,
    /// (owner, member): methods and associated items of `impl`/`trait` blocks, variants of an
    /// enum, fields of a struct, `default` of a type deriving `Default`.
    owned: HashSet<(String, String)>,
    /// Names defined in each file (repository-relative path).
    by_file: HashMap<String, HashSet<String>>,
    /// Contents of string literals.
    strings: HashSet<String>,
    /// Every identifier, definition or use (for flags, which clap derives from field names).
    idents: HashSet<String>,
}

/// What the checker knows of the tree: its files and directories, the text of its Markdown
/// files and the items of its sources. Built from disk, or by hand in the unit tests.
#[derive(Default)]
struct Tree {
    /// Repository-relative paths of files, `/`-separated.
    files: BTreeSet<String>,
    /// Repository-relative paths of directories.
    dirs: BTreeSet<String>,
    /// Markdown and other cited texts by path (for anchors and section titles).
    texts: BTreeMap<String, String>,
    /// Package name → directory (`bdpm-mis` → `crates/mis`; the root package → ``).
    packages: BTreeMap<String, String>,
    items: Items,
}

// ---------------------------------------------------------------- lexing the sources

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Str(String),
    Punct(&'static str),
    Other,
}

fn lex(src: &str) -> Vec<Tok> {
    let b: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_whitespace() {
            i += 1;
        } else if c == '/' && b.get(i + 1) == Some(&'/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && b.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == '"' || ((c == 'r' || c == 'b') && raw_or_byte_string_at(&b, i)) {
            let (s, next) = string_at(&b, i);
            out.push(Tok::Str(s));
            i = next;
        } else if c == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            if b.get(i + 2) == Some(&'\'') {
                i += 3;
            } else if b.get(i + 1) == Some(&'\\') {
                i += 3;
                while i < b.len() && b[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else {
                i += 1;
                while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                    i += 1;
                }
            }
            out.push(Tok::Other);
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(b[start..i].iter().collect()));
        } else if c.is_ascii_digit() {
            while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_' || b[i] == '.') {
                if b[i] == '.' && !b.get(i + 1).is_some_and(|d| d.is_ascii_digit()) {
                    break;
                }
                i += 1;
            }
            out.push(Tok::Other);
        } else {
            let two: String = b[i..(i + 2).min(b.len())].iter().collect();
            let p = match two.as_str() {
                "::" => Some("::"),
                "->" => Some("->"),
                "=>" => Some("=>"),
                _ => None,
            };
            if let Some(p) = p {
                out.push(Tok::Punct(p));
                i += 2;
            } else {
                out.push(Tok::Punct(punct(c)));
                i += 1;
            }
        }
    }
    out
}

fn punct(c: char) -> &'static str {
    match c {
        '{' => "{",
        '}' => "}",
        '(' => "(",
        ')' => ")",
        '[' => "[",
        ']' => "]",
        '<' => "<",
        '>' => ">",
        ',' => ",",
        ';' => ";",
        ':' => ":",
        '#' => "#",
        '!' => "!",
        '=' => "=",
        _ => "?",
    }
}

/// Whether `r"`, `r#"`, `b"`, `br"` or `br#"` starts at `i` (and is not an identifier's tail).
fn raw_or_byte_string_at(b: &[char], i: usize) -> bool {
    if i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_') {
        return false;
    }
    let mut j = i;
    if b[j] == 'b' {
        j += 1;
    }
    if b.get(j) == Some(&'r') {
        j += 1;
        while b.get(j) == Some(&'#') {
            j += 1;
        }
    }
    j > i && b.get(j) == Some(&'"')
}

/// The contents of the string literal starting at `i` and the index after it.
fn string_at(b: &[char], mut i: usize) -> (String, usize) {
    let mut raw = false;
    if b[i] == 'b' {
        i += 1;
    }
    if b[i] == 'r' {
        raw = true;
        i += 1;
    }
    let mut hashes = 0;
    while b[i] == '#' {
        hashes += 1;
        i += 1;
    }
    i += 1; // the opening quote
    let start = i;
    loop {
        if i >= b.len() {
            return (b[start..].iter().collect(), i);
        }
        if !raw && b[i] == '\\' {
            i += 2;
            continue;
        }
        if b[i] == '"' && (0..hashes).all(|k| b.get(i + 1 + k) == Some(&'#')) {
            return (b[start..i].iter().collect(), i + 1 + hashes);
        }
        i += 1;
    }
}

// ---------------------------------------------------------------- indexing definitions

/// What a `{` opens, for the names defined inside it.
#[derive(Clone)]
enum Block {
    /// `impl` or `trait` block: methods and associated items belong to these owners.
    Owners(Vec<String>),
    /// An enum's body: its top-level names are variants.
    Enum(String),
    /// A struct's or union's body: its top-level `name:` are fields.
    Struct(String),
    Other,
}

/// The header that the next `{` will open, seen before it.
enum Pending {
    None,
    Impl(usize),
    Named(&'static str, String),
}

fn ident(t: Option<&Tok>) -> Option<&str> {
    match t {
        Some(Tok::Ident(s)) => Some(s),
        _ => None,
    }
}

fn is_punct(t: Option<&Tok>, p: &str) -> bool {
    matches!(t, Some(Tok::Punct(q)) if *q == p)
}

/// The owners of an `impl` block whose keyword is at `start`: the implementing type, and the
/// trait when there is one (`impl<T> Trait for Type<T> where … {`).
fn impl_owners(toks: &[Tok], start: usize) -> Vec<String> {
    let mut i = start + 1;
    if is_punct(toks.get(i), "<") {
        let mut depth = 0;
        while i < toks.len() {
            if is_punct(toks.get(i), "<") {
                depth += 1;
            } else if is_punct(toks.get(i), ">") {
                depth -= 1;
                if depth == 0 {
                    i += 1;
                    break;
                }
            }
            i += 1;
        }
    }
    // Last identifier of each path at angle depth 0, split by `for`.
    let mut paths: Vec<String> = vec![String::new()];
    let mut angle = 0;
    while i < toks.len() {
        match &toks[i] {
            Tok::Punct("{") | Tok::Punct(";") => break,
            Tok::Ident(s) if angle == 0 && s == "where" => break,
            Tok::Ident(s) if angle == 0 && s == "for" => paths.push(String::new()),
            Tok::Ident(s) if angle == 0 && s != "dyn" && s != "unsafe" => {
                *paths.last_mut().unwrap() = s.clone();
            }
            Tok::Punct("<") => angle += 1,
            Tok::Punct(">") => angle -= 1,
            _ => {}
        }
        i += 1;
    }
    paths.into_iter().filter(|p| !p.is_empty()).collect()
}

impl Items {
    fn define(&mut self, file: &str, name: &str, owners: &[String]) {
        self.defs.insert(name.to_string());
        self.by_file
            .entry(file.to_string())
            .or_default()
            .insert(name.to_string());
        for o in owners {
            self.owned.insert((o.clone(), name.to_string()));
        }
    }

    /// Indexes one source file.
    fn add_file(&mut self, file: &str, src: &str) {
        let toks = lex(src);
        // What each open brace opens.
        let mut blocks: Vec<Block> = Vec::new();
        let mut pending = Pending::None;
        let mut derives: Vec<String> = Vec::new();
        let mut i = 0;
        while i < toks.len() {
            let prev = if i > 0 { toks.get(i - 1) } else { None };
            match &toks[i] {
                Tok::Str(s) => {
                    self.strings.insert(s.clone());
                }
                Tok::Punct("#") if is_punct(toks.get(i + 1), "[") => {
                    i = self.attribute(&toks, i + 1, &mut derives);
                    continue;
                }
                Tok::Punct(";") => pending = Pending::None,
                Tok::Punct("{") => {
                    let block = match std::mem::replace(&mut pending, Pending::None) {
                        Pending::Impl(at) => Block::Owners(impl_owners(&toks, at)),
                        Pending::Named("trait", n) => Block::Owners(vec![n]),
                        Pending::Named("enum", n) => Block::Enum(n),
                        Pending::Named(_, n) => Block::Struct(n),
                        Pending::None => Block::Other,
                    };
                    blocks.push(block);
                    self.member_at_block_start(file, &toks, i, &blocks);
                }
                Tok::Punct("}") => {
                    blocks.pop();
                }
                Tok::Punct(",") => self.member_at_block_start(file, &toks, i, &blocks),
                Tok::Ident(kw) => {
                    self.idents.insert(kw.clone());
                    self.keyword(file, &toks, i, prev, &blocks, &mut pending, &mut derives);
                }
                _ => {}
            }
            i += 1;
        }
    }

    /// Skips the attribute whose `[` is at `i`, noting the traits of a `derive`.
    fn attribute(&mut self, toks: &[Tok], mut i: usize, derives: &mut Vec<String>) -> usize {
        let is_derive = ident(toks.get(i + 1)) == Some("derive");
        let mut depth = 0;
        while i < toks.len() {
            match &toks[i] {
                Tok::Punct("[") => depth += 1,
                Tok::Punct("]") => {
                    depth -= 1;
                    if depth == 0 {
                        return i + 1;
                    }
                }
                Tok::Ident(s) if is_derive => derives.push(s.clone()),
                _ => {}
            }
            i += 1;
        }
        i
    }

    /// An item keyword at `i`: records the name it defines.
    #[allow(clippy::too_many_arguments)]
    fn keyword(
        &mut self,
        file: &str,
        toks: &[Tok],
        i: usize,
        prev: Option<&Tok>,
        blocks: &[Block],
        pending: &mut Pending,
        derives: &mut Vec<String>,
    ) {
        let kw = ident(toks.get(i)).unwrap_or("");
        let owners: Vec<String> = match blocks.last() {
            Some(Block::Owners(o)) => o.clone(),
            _ => Vec::new(),
        };
        let item_start = prev.is_none()
            || matches!(prev, Some(Tok::Punct("}" | ";" | "{" | "]")))
            || matches!(prev, Some(Tok::Ident(s)) if s == "unsafe" || s == "default" || s == "pub");
        match kw {
            "impl" if item_start => *pending = Pending::Impl(i),
            "fn" | "const" | "static" | "type" | "mod" => {
                let mut j = i + 1;
                if ident(toks.get(j)) == Some("mut") {
                    j += 1;
                }
                if let Some(name) = ident(toks.get(j))
                    && name != "fn"
                    && name != "_"
                {
                    self.define(file, name, &owners);
                    if kw == "type" {
                        self.types.insert(name.to_string());
                    }
                }
            }
            "struct" | "enum" | "trait" | "union" => {
                if let Some(name) = ident(toks.get(i + 1)) {
                    self.define(file, name, &[]);
                    self.types.insert(name.to_string());
                    if derives.iter().any(|d| d == "Default") {
                        self.owned.insert((name.to_string(), "default".to_string()));
                    }
                    derives.clear();
                    let kind = match kw {
                        "enum" => "enum",
                        "trait" => "trait",
                        _ => "struct",
                    };
                    *pending = Pending::Named(kind, name.to_string());
                }
            }
            "macro_rules" if is_punct(toks.get(i + 1), "!") => {
                if let Some(name) = ident(toks.get(i + 2)) {
                    self.define(file, name, &[]);
                }
            }
            _ => {}
        }
    }

    /// After the `{` or `,` at `i` at the top level of an enum or struct body: the variant or
    /// field that follows (attributes and `pub(…)` skipped).
    fn member_at_block_start(&mut self, file: &str, toks: &[Tok], i: usize, blocks: &[Block]) {
        let Some(block) = blocks.last() else {
            return;
        };
        if !matches!(block, Block::Enum(_) | Block::Struct(_)) {
            return;
        }
        // Only at the body's own level: not inside a variant's tuple or a field's type.
        let depth_ok = match toks[i] {
            Tok::Punct("{") => true,
            _ => comma_at_body_level(toks, i),
        };
        if !depth_ok {
            return;
        }
        let mut j = i + 1;
        loop {
            if is_punct(toks.get(j), "#") {
                let mut depth = 0;
                j += 1;
                while j < toks.len() {
                    if is_punct(toks.get(j), "[") {
                        depth += 1;
                    } else if is_punct(toks.get(j), "]") {
                        depth -= 1;
                        if depth == 0 {
                            j += 1;
                            break;
                        }
                    }
                    j += 1;
                }
            } else if ident(toks.get(j)) == Some("pub") {
                j += 1;
                if is_punct(toks.get(j), "(") {
                    while j < toks.len() && !is_punct(toks.get(j), ")") {
                        j += 1;
                    }
                    j += 1;
                }
            } else {
                break;
            }
        }
        let Some(name) = ident(toks.get(j)) else {
            return;
        };
        match block {
            Block::Enum(owner) => {
                self.define(file, name, std::slice::from_ref(owner));
                self.types.insert(name.to_string());
            }
            Block::Struct(owner) if is_punct(toks.get(j + 1), ":") => {
                self.define(file, name, std::slice::from_ref(owner));
            }
            _ => {}
        }
    }
}

/// Whether the `,` at `i` is at the paren depth its enclosing block was opened at (a variant
/// or field separator, not a comma inside a tuple variant or a generic type).
fn comma_at_body_level(toks: &[Tok], i: usize) -> bool {
    // Walk back to the block's `{`, counting parens, brackets and angle brackets.
    let mut depth = 0i32;
    let mut braces = 0i32;
    let mut j = i;
    while j > 0 {
        j -= 1;
        match toks[j] {
            Tok::Punct(")" | "]" | ">") => depth += 1,
            Tok::Punct("(" | "[" | "<") => depth -= 1,
            Tok::Punct("}") => braces += 1,
            Tok::Punct("{") => {
                if braces == 0 {
                    return depth == 0;
                }
                braces -= 1;
            }
            _ => {}
        }
    }
    false
}

// ---------------------------------------------------------------- the tree from disk

fn walk(root: &Path, rel: &str, tree: &mut Tree, sources: &mut Vec<(String, String)>) {
    let Ok(entries) = fs::read_dir(root.join(rel)) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let path = if rel.is_empty() {
            name.clone()
        } else {
            format!("{rel}/{name}")
        };
        let Ok(kind) = e.file_type() else { continue };
        if kind.is_dir() {
            if rel.is_empty() && (name == "target" || name == "out" || name.starts_with('.')) {
                continue;
            }
            tree.dirs.insert(path.clone());
            walk(root, &path, tree, sources);
        } else {
            if name.ends_with(".md") {
                tree.texts.insert(path.clone(), read(root, &path));
            }
            let cited_source = ["crates/", "tests/", "benches/"]
                .iter()
                .any(|r| path.starts_with(r));
            if name.ends_with(".rs") && cited_source {
                sources.push((path.clone(), read(root, &path)));
            }
            if name == "Cargo.toml" {
                let text = read(root, &path);
                if let Some(pkg) = package_name(&text) {
                    let dir = path.trim_end_matches("Cargo.toml").trim_end_matches('/');
                    tree.packages.insert(pkg, dir.to_string());
                }
            }
            tree.files.insert(path);
        }
    }
}

fn read(root: &Path, rel: &str) -> String {
    fs::read_to_string(root.join(rel)).unwrap_or_default()
}

/// The `name` of a manifest's `[package]` table.
fn package_name(manifest: &str) -> Option<String> {
    let pkg = manifest.split("[package]").nth(1)?;
    let line = pkg.lines().find(|l| l.trim_start().starts_with("name"))?;
    Some(line.split('"').nth(1)?.to_string())
}

impl Tree {
    fn from_disk(root: &Path) -> Tree {
        let mut tree = Tree::default();
        let mut sources = Vec::new();
        walk(root, "", &mut tree, &mut sources);
        for (path, src) in &sources {
            tree.items.add_file(path, src);
        }
        tree
    }

    fn exists(&self, path: &str) -> bool {
        let p = path.trim_end_matches('/');
        p.is_empty() || self.files.contains(p) || self.dirs.contains(p)
    }

    /// Whether a path with placeholders matches something: `*`, `{a,b}`, `<name>` and
    /// all-capital words (`SCENE`, `X`) stand for any part of a name.
    fn exists_pattern(&self, path: &str) -> bool {
        if self.exists(path) {
            return true;
        }
        expand_braces(path).iter().all(|p| {
            let pat = placeholders_to_stars(p);
            let pat = pat.trim_end_matches('/');
            if !pat.contains('*') {
                return self.exists(pat);
            }
            self.files
                .iter()
                .chain(self.dirs.iter())
                .any(|f| glob_match(pat, f))
        })
    }
}

fn expand_braces(path: &str) -> Vec<String> {
    let (Some(a), Some(b)) = (path.find('{'), path.find('}')) else {
        return vec![path.to_string()];
    };
    if b < a {
        return vec![path.to_string()];
    }
    let mut out = Vec::new();
    for alt in path[a + 1..b].split(',') {
        out.extend(expand_braces(&format!(
            "{}{}{}",
            &path[..a],
            alt,
            &path[b + 1..]
        )));
    }
    out
}

/// `<name>`, whole all-capital words (between `/`, `-`, `.`, `_`) and one-letter file stems
/// become `*`.
fn placeholders_to_stars(path: &str) -> String {
    let mut s = String::new();
    let mut rest = path;
    while let Some(a) = rest.find('<') {
        let Some(b) = rest[a..].find('>') else { break };
        s.push_str(&rest[..a]);
        s.push('*');
        rest = &rest[a + b + 1..];
    }
    s.push_str(rest);
    let mut out = String::new();
    let mut word = String::new();
    for c in s.chars().chain(std::iter::once('\0')) {
        if c.is_alphanumeric() {
            word.push(c);
            continue;
        }
        let capital = !word.is_empty()
            && word
                .chars()
                .all(|w| w.is_ascii_uppercase() || w.is_ascii_digit())
            && word.chars().next().is_some_and(|w| w.is_ascii_uppercase());
        // A one-letter name (`scenes/x.toml`, `meshes/a.gltf`) is an example too.
        let capital = capital || (word.chars().count() == 1 && c == '.');
        out.push_str(if capital { "*" } else { &word });
        word.clear();
        if c != '\0' {
            out.push(c);
        }
    }
    out
}

/// `*` matches any run of characters within one path component.
fn glob_match(pat: &str, path: &str) -> bool {
    let pc: Vec<&str> = pat.split('/').collect();
    let fc: Vec<&str> = path.split('/').collect();
    pc.len() == fc.len() && pc.iter().zip(&fc).all(|(p, f)| component_match(p, f))
}

fn component_match(pat: &str, s: &str) -> bool {
    let parts: Vec<&str> = pat.split('*').collect();
    if parts.len() == 1 {
        return pat == s;
    }
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if !s.starts_with(first) || !s[first.len()..].ends_with(last) {
        return false;
    }
    let mut rest = &s[first.len()..s.len() - last.len()];
    for mid in &parts[1..parts.len() - 1] {
        match rest.find(mid) {
            Some(k) => rest = &rest[k + mid.len()..],
            None => return false,
        }
    }
    true
}

// ---------------------------------------------------------------- finding claims in Markdown

/// A Markdown file split into prose (fenced blocks blanked) and its fenced code lines.
struct Doc<'a> {
    path: &'a str,
    prose: String,
    /// Lines of fenced blocks.
    code: Vec<String>,
    /// Lines of fenced blocks that hold commands or files (not untagged or ```text blocks,
    /// which show output and syntax such as `scenes/x.toml: material.red.kd: …`).
    commands: Vec<String>,
}

fn split_fences<'a>(path: &'a str, text: &str) -> Doc<'a> {
    let mut doc = Doc {
        path,
        prose: String::new(),
        code: Vec::new(),
        commands: Vec::new(),
    };
    let mut fence: Option<bool> = None;
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("```") || t.starts_with("~~~") {
            fence = match fence {
                Some(_) => None,
                None => {
                    let tag = t.trim_start_matches(['`', '~']).trim();
                    Some(!tag.is_empty() && tag != "text")
                }
            };
            doc.prose.push('\n');
        } else if let Some(commands) = fence {
            doc.code.push(line.to_string());
            if commands {
                doc.commands.push(line.to_string());
            }
            doc.prose.push('\n');
        } else {
            doc.prose.push_str(line);
            doc.prose.push('\n');
        }
    }
    doc
}

/// Inline code spans of prose (single or double backticks; a span may wrap onto the next
/// line but not across a blank line), with newlines as spaces.
fn code_spans(prose: &str) -> Vec<String> {
    let c: Vec<char> = prose.chars().collect();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if c[i] != '`' {
            i += 1;
            continue;
        }
        let mut n = 0;
        while i + n < c.len() && c[i + n] == '`' {
            n += 1;
        }
        let start = i + n;
        let mut j = start;
        let mut found = None;
        while j < c.len() {
            if c[j] == '\n' && c.get(j + 1) == Some(&'\n') {
                break;
            }
            if c[j] == '`' {
                let mut m = 0;
                while j + m < c.len() && c[j + m] == '`' {
                    m += 1;
                }
                if m == n {
                    found = Some(j);
                    break;
                }
                j += m;
                continue;
            }
            j += 1;
        }
        match found {
            Some(end) => {
                let s: String = c[start..end].iter().collect();
                spans.push(s.replace('\n', " ").trim().to_string());
                i = end + n;
            }
            None => i = start,
        }
    }
    spans
}

fn is_path_char(c: char) -> bool {
    c.is_alphanumeric() || "_-./*<>…".contains(c)
}

/// Repository paths cited in text: a token starting with one of `ROOTS` (after a character
/// that cannot be part of a path), with `{a,b}` groups; trailing punctuation dropped. A
/// following `::name` is returned too (`tests/suite/cornell.rs::name`).
fn cited_paths(text: &str) -> Vec<(String, Option<String>)> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts = ROOTS.iter().find(|r| {
            let r: Vec<char> = r.chars().collect();
            c[i..].starts_with(&r) && (i == 0 || !(is_path_char(c[i - 1]) || c[i - 1] == '/'))
        });
        if starts.is_none() {
            i += 1;
            continue;
        }
        let start = i;
        while i < c.len() {
            if c[i] == '{' {
                match c[i..].iter().position(|&d| d == '}') {
                    Some(k) if !c[i..i + k].contains(&' ') => i += k + 1,
                    _ => break,
                }
            } else if is_path_char(c[i]) {
                i += 1;
            } else {
                break;
            }
        }
        let mut p: String = c[start..i].iter().collect();
        while p.ends_with(['.', ',', ':', '…', '-']) || p.ends_with("...") {
            p.pop();
        }
        let mut item = None;
        if c[i..].starts_with(&[':', ':']) {
            let k = i + 2;
            let mut e = k;
            while e < c.len()
                && (c[e].is_alphanumeric() || c[e] == '_' || c[e] == '*' || c[e] == '…')
            {
                e += 1;
            }
            item = Some(c[k..e].iter().collect());
            i = e;
        }
        out.push((p, item));
    }
    out
}

/// Markdown link targets `](target)` (not web or mail links).
fn link_targets(prose: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = prose;
    while let Some(k) = rest.find("](") {
        rest = &rest[k + 2..];
        let Some(end) = rest.find(')') else { break };
        let t = rest[..end].trim();
        if !(t.starts_with("http:") || t.starts_with("https:") || t.starts_with("mailto:")) {
            out.push(t.to_string());
        }
        rest = &rest[end..];
    }
    out
}

/// GitHub's anchor of a heading: lower case, characters other than letters, digits, `_`,
/// `-` and spaces dropped, spaces as `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '_' || *c == '-' || *c == ' ')
        .flat_map(char::to_lowercase)
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings (repeats numbered as GitHub does).
fn anchors(text: &str) -> HashSet<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = HashSet::new();
    let doc = split_fences("", text);
    for line in doc.prose.lines() {
        let t = line.trim_start();
        if !t.starts_with('#') {
            continue;
        }
        let s = slug(t.trim_start_matches('#'));
        let n = seen.entry(s.clone()).or_insert(0);
        out.insert(if *n == 0 {
            s.clone()
        } else {
            format!("{s}-{n}")
        });
        *n += 1;
    }
    out
}

/// Joins a directory and a relative link, resolving `.` and `..`.
fn join(dir: &str, rel: &str) -> String {
    let mut parts: Vec<&str> = dir.split('/').filter(|p| !p.is_empty()).collect();
    for p in rel.split('/') {
        match p {
            "." | "" => {}
            ".." => {
                parts.pop();
            }
            _ => parts.push(p),
        }
    }
    parts.join("/")
}

fn dir_of(path: &str) -> &str {
    path.rfind('/').map_or("", |k| &path[..k])
}

/// Section titles cited as `FILE.md, "Title"` or `FILE.md ("Title")`: (file as written,
/// title). Line breaks and comment markers inside the title are read as spaces.
fn cited_sections(text: &str) -> Vec<(String, String)> {
    let flat: String = text
        .lines()
        .map(|l| {
            l.trim_start()
                .trim_start_matches("//!")
                .trim_start_matches("///")
                .trim_start_matches("//")
                .trim_start_matches('#')
                .trim()
        })
        .collect::<Vec<_>>()
        .join(" ");
    let mut out = Vec::new();
    let mut rest = flat.as_str();
    while let Some(k) = rest.find(".md") {
        let before = &rest[..k];
        let after = &rest[k + 3..];
        let name_start = before
            .rfind(|c: char| !(c.is_alphanumeric() || "_-./".contains(c)))
            .map_or(0, |s| s + 1);
        let file = format!("{}.md", &before[name_start..]);
        let quoted = after
            .strip_prefix(", \"")
            .or_else(|| after.strip_prefix(" (\""));
        if let Some(q) = quoted
            && let Some(end) = q.find('"')
        {
            out.push((file, q[..end].to_string()));
        }
        rest = after;
    }
    out
}

fn collapse(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

// ---------------------------------------------------------------- checking claims

/// `CamelCase` (no `_`: `T_jitter`, `TEXCOORD_n` are symbols, not items).
fn is_camel(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_uppercase())
        && s.chars().any(|c| c.is_ascii_lowercase())
        && !s.contains('_')
}

/// `SCREAMING_CASE` with a word of two letters or more before the first `_` (`N_F`, `O_EXCL`
/// are a symbol and a libc flag).
fn is_screaming(s: &str) -> bool {
    let first = s.split('_').next().unwrap_or("");
    s.contains('_')
        && first.len() >= 2
        && s.chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
}

/// The Rust path a code span names, if the span is one (`A::b`, `A::b()`, `f(args)`,
/// `snake_name`, `CamelName`, `CONST_NAME`): the segments and whether it was called.
fn rust_path(span: &str) -> Option<(Vec<String>, bool)> {
    let end = span
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(span.len());
    let (path, tail) = span.split_at(end);
    let called = tail.starts_with('(');
    if !(tail.is_empty() || called) || path.is_empty() || path.ends_with(':') {
        return None;
    }
    let segs: Vec<String> = path.split("::").map(str::to_string).collect();
    let ok = segs.iter().all(|s| {
        !s.is_empty()
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !s.starts_with(|c: char| c.is_ascii_digit())
    });
    if !ok {
        return None;
    }
    let one = &segs[0];
    let claim = segs.len() > 1
        || called
        || is_camel(one)
        || is_screaming(one)
        || (one.contains('_')
            && one
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'));
    claim.then_some((segs, called))
}

impl Tree {
    /// Whether a crate segment (`bdpm_mis`) names a package of the workspace.
    fn is_crate(&self, seg: &str) -> bool {
        self.packages.contains_key(&seg.replace('_', "-"))
    }

    /// Checks a Rust path; `Err` says what is missing.
    fn check_rust_path(&self, segs: &[String]) -> Result<(), String> {
        let it = &self.items;
        let mut segs: Vec<&str> = segs.iter().map(String::as_str).collect();
        if EXTERNAL.contains(&segs[0]) || SEESHARP.contains(&segs[0]) {
            return Ok(());
        }
        while segs.len() > 1
            && (self.is_crate(segs[0]) || ["crate", "self", "super"].contains(&segs[0]))
        {
            segs.remove(0);
        }
        if segs.len() == 1 && self.is_crate(segs[0]) {
            return Ok(());
        }
        // Module segments: a `mod`, a file stem or a crate's directory name.
        while segs.len() > 1 && !is_camel(segs[0]) && !is_screaming(segs[0]) {
            let m = segs[0];
            let known = it.defs.contains(m)
                || self.files.iter().any(|f| f.ends_with(&format!("/{m}.rs")))
                || self.dirs.contains(&format!("crates/{m}"));
            if !known {
                return Err(format!("no module `{m}`"));
            }
            segs.remove(0);
        }
        match segs.as_slice() {
            [one] if is_camel(one) => (it.types.contains(*one) || it.defs.contains(*one))
                .then_some(())
                .ok_or(format!("no type, trait or variant `{one}`")),
            [one] => (it.defs.contains(*one)
                || it.strings.contains(*one)
                || self
                    .files
                    .iter()
                    .any(|f| f.ends_with(&format!("/{one}.rs"))))
            .then_some(())
            .ok_or(format!("no item `{one}`")),
            [.., owner, member] => {
                if !it.types.contains(*owner) {
                    return Err(format!("no type, trait or enum `{owner}`"));
                }
                it.owned
                    .contains(&(owner.to_string(), member.to_string()))
                    .then_some(())
                    .ok_or(format!("`{owner}` has no `{member}`"))
            }
            [] => Ok(()),
        }
    }

    /// Checks one flag of `bdpm` (without the dashes): clap derives it from a field or names
    /// it in a string.
    fn check_flag(&self, flag: &str) -> Result<(), String> {
        let it = &self.items;
        let field = flag.replace('-', "_");
        let found = FOREIGN_FLAGS.contains(&flag)
            || it.idents.contains(&field)
            || it.strings.contains(flag)
            || it.strings.contains(&format!("--{flag}"));
        found.then_some(()).ok_or(format!("no flag `--{flag}`"))
    }
}

/// Flags of `bdpm` in one command line (a code line or span): the ones after `bdpm` (or after
/// `cargo run … --`); all of them when the line is a continuation or a lone flag.
fn bdpm_flags(line: &str, continuation: bool) -> Vec<String> {
    let toks: Vec<&str> = line.split_whitespace().collect();
    let from = match bdpm_invocation(&toks) {
        Some(f) => f,
        None if continuation || toks.first().is_some_and(|t| t.starts_with("--")) => 0,
        None => return Vec::new(),
    };
    toks[from..]
        .iter()
        .map(|t| t.trim_start_matches(['[', '(']))
        .filter(|t| t.starts_with("--") && t.len() > 2)
        .map(|t| {
            t[2..]
                .split(['=', ']', ')', '|', ','])
                .next()
                .unwrap_or("")
                .to_string()
        })
        .filter(|f| !f.is_empty() && f.chars().all(|c| c.is_ascii_lowercase() || c == '-'))
        .collect()
}

/// Where the arguments of `bdpm` start in a command line's words: after `bdpm` (or a path
/// ending in `/bdpm`, not `-p bdpm`), or after the `--` of `cargo run`.
fn bdpm_invocation(toks: &[&str]) -> Option<usize> {
    toks.iter().enumerate().find_map(|(k, t)| {
        let prev = if k > 0 { toks[k - 1] } else { "" };
        let is_bdpm = (*t == "bdpm" || t.ends_with("/bdpm")) && prev != "-p";
        let cargo_run = toks.first() == Some(&"cargo") && toks.get(1) == Some(&"run");
        (is_bdpm || (*t == "--" && cargo_run)).then_some(k + 1)
    })
}

/// `-p PACKAGE --example NAME` / `--bench NAME` in a command line: the file they need.
fn cargo_targets(line: &str) -> Vec<String> {
    let toks: Vec<&str> = line.split_whitespace().collect();
    let pkg = toks
        .windows(2)
        .find(|w| w[0] == "-p")
        .map(|w| w[1].to_string());
    let placeholder = |w: &str| w.chars().all(|c| c.is_ascii_uppercase());
    let mut out = Vec::new();
    if pkg.as_deref().is_some_and(placeholder) {
        return out;
    }
    for w in toks.windows(2) {
        let kind = match w[0] {
            "--example" => "examples",
            "--bench" => "benches",
            _ => continue,
        };
        for name in w[1]
            .split('|')
            .filter(|n| !placeholder(n) && !n.starts_with('<'))
        {
            out.push(format!(
                "{}\u{0}{kind}/{name}.rs",
                pkg.clone().unwrap_or_default()
            ));
        }
    }
    out
}

/// Every claim of one Markdown file that does not hold, as `file: claim: what is wrong`.
fn check_doc(tree: &Tree, path: &str, text: &str, links_only: bool) -> Vec<String> {
    let doc = split_fences(path, text);
    let mut bad = Vec::new();
    let mut fail = |claim: &str, why: String| bad.push(format!("{}: {claim}: {why}", doc.path));
    check_links(tree, &doc, &mut fail);
    if links_only {
        return bad;
    }
    let spans = code_spans(&doc.prose);
    let mut lines: Vec<(String, bool)> = Vec::new();
    let mut in_bdpm = false;
    for l in &doc.code {
        let cont = l.starts_with(char::is_whitespace) || l.trim_start().starts_with('[');
        lines.push((l.clone(), cont && in_bdpm));
        if !cont {
            let words: Vec<&str> = l.split_whitespace().collect();
            in_bdpm = bdpm_invocation(&words).is_some();
        }
    }
    lines.extend(spans.iter().map(|s| (s.clone(), false)));
    for (line, cont) in &lines {
        for f in bdpm_flags(line, *cont) {
            if let Err(e) = tree.check_flag(&f) {
                fail(&format!("`--{f}`"), e);
            }
        }
        for t in cargo_targets(line) {
            let (pkg, file) = t.split_once('\u{0}').unwrap_or_default();
            let dir = tree
                .packages
                .get(if pkg.is_empty() { "bdpm-suite" } else { pkg });
            let ok = dir.is_some_and(|d| {
                tree.exists(&join(d, file))
                    || tree.exists(&join(d, &file.replace(".rs", "/main.rs")))
            });
            if !ok {
                fail(line.trim(), format!("no `{file}` in package `{pkg}`"));
            }
        }
    }
    for span in spans.iter().filter(|s| !REMOVED.contains(&s.as_str())) {
        if let Some((segs, _)) = rust_path(span) {
            if let Err(e) = tree.check_rust_path(&segs) {
                fail(&format!("`{span}`"), e);
            }
        } else if let Some(stem) = span.strip_suffix(".rs").filter(|s| !s.contains(['/', ' ']))
            && !tree
                .files
                .iter()
                .any(|f| f.ends_with(&format!("/{stem}.rs")))
        {
            fail(&format!("`{span}`"), "no such file in the tree".into());
        }
    }
    let all_code = doc.commands.join("\n");
    for text in [doc.prose.as_str(), all_code.as_str()] {
        for (p, item) in cited_paths(text) {
            if !tree.exists_pattern(&p) {
                fail(&p, "no such file or directory".into());
            } else if let Some(name) = item {
                let defined = tree.items.by_file.get(&p).is_some_and(|d| {
                    match name.strip_suffix(['*', '…']) {
                        Some(prefix) => d.iter().any(|n| n.starts_with(prefix)),
                        None => d.contains(&name),
                    }
                });
                if !defined {
                    fail(
                        &format!("{p}::{name}"),
                        format!("`{name}` is not defined in {p}"),
                    );
                }
            }
        }
    }
    bad.extend(check_sections(tree, path, text));
    bad
}

/// Relative links resolve to a file or directory, and their `#anchor` to a heading.
fn check_links(tree: &Tree, doc: &Doc, fail: &mut impl FnMut(&str, String)) {
    for t in link_targets(&doc.prose) {
        let (file, anchor) = match t.split_once('#') {
            Some((f, a)) => (f, Some(a)),
            None => (t.as_str(), None),
        };
        let target = if file.is_empty() {
            doc.path.to_string()
        } else {
            join(dir_of(doc.path), file)
        };
        if !tree.exists(&target) {
            fail(&format!("link ({t})"), format!("no {target}"));
            continue;
        }
        if let Some(a) = anchor {
            let has = tree
                .texts
                .get(&target)
                .is_some_and(|x| anchors(x).contains(a));
            if !has {
                fail(
                    &format!("link ({t})"),
                    format!("no heading #{a} in {target}"),
                );
            }
        }
    }
}

/// Sections cited by title (`FILE.md, "Title"`) are in FILE: as a heading or in its text
/// (a page that moved a section says where; a title ending in `…` is a prefix).
fn check_sections(tree: &Tree, path: &str, text: &str) -> Vec<String> {
    let mut bad = Vec::new();
    for (file, title) in cited_sections(text) {
        let target = if file.contains('/') {
            if tree.texts.contains_key(&file) {
                file.clone()
            } else {
                join(dir_of(path), &file)
            }
        } else {
            let here = join(dir_of(path), &file);
            if tree.texts.contains_key(&here) {
                here
            } else {
                format!("docs/{file}")
            }
        };
        let Some(body) = tree.texts.get(&target) else {
            bad.push(format!("{path}: {file}, \"{title}\": no {target}"));
            continue;
        };
        let want = collapse(title.trim_end_matches('…').trim_end_matches("..."));
        if !collapse(body).contains(&want) {
            bad.push(format!("{path}: {file}, \"{title}\": not in {target}"));
        }
    }
    bad
}

/// The Markdown files the check reads, and whether only their links are checked.
fn docs_to_check(tree: &Tree) -> Vec<(&String, bool)> {
    tree.texts
        .keys()
        .filter(|p| {
            *p == "README.md" || (p.starts_with("docs/") && !p.starts_with("docs/results/"))
        })
        .map(|p| (p, p.starts_with("docs/notebook/")))
        .collect()
}

/// Every failing claim of the docs, and the section titles cited from code, scripts and scenes.
fn check_tree(root: &Path, tree: &Tree) -> Vec<String> {
    let mut bad = Vec::new();
    for (path, links_only) in docs_to_check(tree) {
        bad.extend(check_doc(tree, path, &tree.texts[path], links_only));
    }
    let cited_from = ["crates/", "tests/", "benches/", "scripts/", "scenes/"];
    for f in &tree.files {
        // This file's own examples of citations are fixtures, not citations.
        let own = f == "tests/suite/doc_claims.rs";
        if cited_from.iter().any(|r| f.starts_with(r)) && !f.ends_with(".md") && !own {
            let text = read(root, f);
            if text.contains(".md") {
                bad.extend(check_sections(tree, f, &text));
            }
        }
    }
    bad
}

#[test]
fn every_path_item_flag_link_and_section_the_docs_cite_exists() {
    let t0 = std::time::Instant::now();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::from_disk(root);
    let bad = check_tree(root, &tree);
    let n_docs = docs_to_check(&tree).len();
    assert!(n_docs >= 8, "read only {n_docs} Markdown files");
    assert!(
        bad.is_empty(),
        "{} claims of the docs do not hold:\n{}",
        bad.len(),
        bad.join("\n")
    );
    eprintln!(
        "doc claims: {n_docs} files checked in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
}

/// A small tree by hand: one source file, a few files and one Markdown target.
fn fake_tree() -> Tree {
    let mut t = Tree::default();
    for f in [
        "crates/a/src/lib.rs",
        "crates/a/Cargo.toml",
        "crates/a/examples/demo.rs",
        "scenes/box.toml",
        "docs/results.md",
    ] {
        t.files.insert(f.to_string());
    }
    for d in [
        "crates",
        "crates/a",
        "crates/a/src",
        "crates/a/examples",
        "scenes",
        "docs",
    ] {
        t.dirs.insert(d.to_string());
    }
    t.packages.insert("bdpm-a".into(), "crates/a".into());
    t.texts.insert(
        "docs/results.md".into(),
        "# Results\n\n## Current defaults\n\nMoved: \"A scene that sets nothing\".\n".into(),
    );
    let src = r#"
        /// `Renderer` in a comment is not a definition: `NotDefined`.
        pub struct Renderer { pub passes: u32, radius_m: f32 }
        #[derive(Debug, Default)]
        pub struct Settings { pub cache_bins: usize }
        pub enum Stage { Photons, Camera(u32), Pilot { n: u32 } }
        impl Renderer { pub fn new() -> Self { todo!() } fn stages(&self) {} }
        impl std::fmt::Display for Stage { fn fmt(&self) {} }
        pub const DEFAULT_CACHE_BINS: usize = 1;
        pub fn estimate_memory() { let layer = "x0_raw"; }
        #[derive(clap::Args)] struct Overrides { #[arg(long)] adaptive_radius: Option<bool> }
    "#;
    t.items.add_file("crates/a/src/lib.rs", src);
    t
}

#[test]
fn the_checker_finds_what_is_defined_and_refuses_what_is_not() {
    let t = fake_tree();
    let good = "See `crates/a/src/lib.rs`, crates/a/src/lib.rs::estimate_memory, scenes/X.toml, \
        `scenes/{box,box}.toml`, [r](results.md#current-defaults) and [d](../docs/), \
        `Renderer::new`, `Renderer::stages()`, `Stage::Camera`, `Stage::fmt`, `Settings::default()`, \
        `Settings::cache_bins`, `estimate_memory`, `DEFAULT_CACHE_BINS`, `x0_raw`, `bdpm_a::Renderer`, \
        `lib.rs`, `balance`, `radius = \"0.2px\"`, `Serialize`, `--adaptive-radius true` and \
        `bdpm render s.toml --adaptive-radius false` (docs/results.md, \"A scene that sets nothing\"; \
        results.md (\"Current defaults\")).\n\n```sh\ncargo run --release -p bdpm-a --example demo\n```\n";
    let none: Vec<String> = Vec::new();
    assert_eq!(check_doc(&t, "docs/x.md", good, false), none);
    let cases = [
        ("`crates/a/src/gone.rs`", "no such file"),
        ("see crates/b/ here", "no such file"),
        ("crates/a/src/lib.rs::render_pass", "not defined in"),
        ("[r](results.md#old-section)", "no heading"),
        ("[r](notebook/x.md)", "no docs/notebook/x.md"),
        ("`Renderer::render_pass`", "has no `render_pass`"),
        ("`Stage::Mixing`", "has no `Mixing`"),
        ("`Scene::new`", "no type"),
        ("`NotDefined`", "no type"),
        ("`estimate_memry`", "no item"),
        ("`spawn_offset()`", "no item"),
        ("`MODEL_CACHE_BINS`", "no item"),
        ("`gone.rs`", "no such file"),
        ("`bdpm render s.toml --adaptive-radios false`", "no flag"),
        (
            "```sh\ncargo run --release -p bdpm-a --example nope\n```",
            "no `examples/nope.rs`",
        ),
        (
            "docs/results.md, \"Defaults that win at equal time\"",
            "not in docs/results.md",
        ),
    ];
    for (text, why) in cases {
        let bad = check_doc(&t, "docs/x.md", text, false);
        assert!(
            bad.len() == 1 && bad[0].contains(why),
            "{text:?} should fail with {why:?}, got {bad:?}"
        );
    }
    // The notebook: links are checked, prose is history.
    assert!(
        check_doc(
            &t,
            "docs/notebook/a.md",
            "`Scene::new`, crates/b/x.rs",
            true
        )
        .is_empty()
    );
    assert_eq!(
        check_doc(&t, "docs/notebook/a.md", "[r](../nope.md)", true).len(),
        1
    );
}

#[test]
fn a_claim_about_the_real_tree_that_does_not_hold_fails() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::from_disk(root);
    let real = "`Renderer::new`, `bdpm_mis::Budget::one_minus_cb`, `PhotonScene`, \
        crates/integrator/src/render.rs and `scripts/bit-check.sh`.";
    assert_eq!(
        check_doc(&tree, "README.md", real, false),
        Vec::<String>::new()
    );
    let fake = "`Renderer::no_such_method`, `NoSuchType`, crates/integrator/src/no_such_file.rs";
    assert_eq!(check_doc(&tree, "README.md", fake, false).len(), 3);
}

#[test]
fn anchors_are_githubs() {
    assert_eq!(
        slug(" Light tracing in BDD=0's place (`light_tracing = true`)"),
        "light-tracing-in-bdd0s-place-light_tracing--true"
    );
    assert_eq!(
        slug(" Current defaults, 256² at 2 threads"),
        "current-defaults-256²-at-2-threads"
    );
    let a = anchors("# A\n\n## A\n\n```\n# not a heading\n```\n");
    assert!(a.contains("a") && a.contains("a-1") && !a.contains("not-a-heading"));
}

//! Stage 1: XML text → an owned element tree with `<include>`, `<default>`, `$name`
//! substitution and `<path>` resolved, every element and attribute carrying its location.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::textpos::TextIndex;
pub use crate::textpos::read_text;
use crate::{LoadError, LoadOptions, Loc, Result, Warning};

/// Mitsuba's limit on nested includes.
const MAX_INCLUDE_DEPTH: usize = 15;
/// Refuse absurdly large documents instead of exhausting memory.
const MAX_NODES: u32 = 20_000_000;
/// Deepest element nesting accepted (checked before recursing, so a hostile file cannot
/// overflow the stack); real scenes nest fewer than ten levels.
pub const MAX_ELEMENT_DEPTH: usize = 256;

#[derive(Clone, Debug)]
pub struct Attr {
    pub name: String,
    pub value: String,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub struct Elem {
    pub tag: String,
    pub attrs: Vec<Attr>,
    pub children: Vec<Elem>,
    pub loc: Loc,
    /// Directory of the file this element was read from (relative paths resolve here first).
    pub dir: Arc<PathBuf>,
}

impl Elem {
    pub fn attr(&self, name: &str) -> Option<&Attr> {
        self.attrs.iter().find(|a| a.name == name)
    }
    pub fn value(&self, name: &str) -> Option<&str> {
        self.attr(name).map(|a| a.value.as_str())
    }
    /// Location of attribute `name`, or of the element when absent.
    pub fn loc_of(&self, name: &str) -> Loc {
        self.attr(name)
            .map_or_else(|| self.loc.clone(), |a| a.loc.clone())
    }
}

/// The parsed document.
pub struct Source {
    pub root: Elem,
    /// Directory of the main file, then `<path>` folders: where relative files are searched.
    pub search_dirs: Vec<PathBuf>,
    pub warnings: Vec<Warning>,
}

pub fn err(loc: &Loc, msg: impl Into<String>) -> LoadError {
    LoadError::new(loc.clone(), msg)
}

struct Param {
    value: String,
    /// Given on the command line (`-D`): overrides `<default>`.
    from_cli: bool,
    used: bool,
}

struct Reader {
    params: HashMap<String, Param>,
    /// Canonical paths of the files being read (include cycle detection).
    stack: Vec<PathBuf>,
    /// For each entry of `stack`, the `<include>` that opened it.
    via: Vec<Loc>,
    search_dirs: Vec<PathBuf>,
    warnings: Vec<Warning>,
}

pub fn read(path: &Path, opts: &LoadOptions) -> Result<Source> {
    let main_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut reader = Reader {
        params: HashMap::new(),
        stack: Vec::new(),
        via: Vec::new(),
        search_dirs: vec![main_dir],
        warnings: Vec::new(),
    };
    for (name, value) in &opts.defines {
        reader.params.insert(
            name.clone(),
            Param {
                value: value.clone(),
                from_cli: true,
                used: false,
            },
        );
    }
    let root = reader.read_file(path, &Loc::file(path))?;
    let mut unused: Vec<&String> = reader
        .params
        .iter()
        .filter(|(_, p)| p.from_cli && !p.used)
        .map(|(n, _)| n)
        .collect();
    unused.sort();
    for name in unused {
        reader.warnings.push(Warning {
            loc: Loc::file(path),
            message: format!("-D {name}: the scene never uses the parameter '${name}'"),
        });
    }
    Ok(Source {
        root,
        search_dirs: reader.search_dirs,
        warnings: reader.warnings,
    })
}

impl Reader {
    /// Parse one file into its root element (includes expanded).
    fn read_file(&mut self, path: &Path, at: &Loc) -> Result<Elem> {
        if self.stack.len() > MAX_INCLUDE_DEPTH {
            return Err(err(
                at,
                format!("more than {MAX_INCLUDE_DEPTH} nested <include>s"),
            ));
        }
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some(i) = self.stack.iter().position(|p| *p == canonical) {
            let chain: Vec<String> = self.stack[i..]
                .iter()
                .chain(std::iter::once(&canonical))
                .map(|p| p.display().to_string())
                .collect();
            // Point at the <include> inside the first file of the cycle.
            let culprit = self.via.get(i + 1).unwrap_or(at);
            return Err(err(
                culprit,
                format!("include cycle: {}", chain.join(" -> ")),
            ));
        }
        let text = read_text(path, at)?;
        let file = Arc::new(path.to_path_buf());
        let opt = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_NODES,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(&text, opt).map_err(|e| {
            use roxmltree::Error as E;
            match e {
                // roxmltree reports these at 1:1; the problem is at the end of the text.
                E::UnclosedRootNode | E::UnexpectedEndOfStream | E::NoRootNode => {
                    let (line, col) = TextIndex::new(&text).pos(text.len());
                    LoadError::new(
                        Loc::new(&file, line, col),
                        format!("malformed XML: unexpected end of file ({e})"),
                    )
                }
                _ => {
                    let p = e.pos();
                    LoadError::new(Loc::new(&file, p.row, p.col), format!("malformed XML: {e}"))
                }
            }
        })?;
        let dir = Arc::new(path.parent().map(Path::to_path_buf).unwrap_or_default());
        self.stack.push(canonical);
        self.via.push(at.clone());
        let ctx = FileCtx {
            index: TextIndex::new(&text),
            file: &file,
            dir: &dir,
        };
        let result = self.convert(&ctx, doc.root_element(), 0);
        self.stack.pop();
        self.via.pop();
        match result? {
            Converted::One(e) => Ok(e),
            Converted::Many(_) | Converted::None => Err(err(
                &ctx.loc(doc.root_element().range().start),
                format!(
                    "<{}> cannot be the root element of a scene file",
                    doc.root_element().tag_name().name()
                ),
            )),
        }
    }

    fn substitute(&mut self, value: &str, loc: &Loc) -> Result<String> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            if len == 0 {
                out.push('$');
                rest = after;
                continue;
            }
            let name = &after[..len];
            match self.params.get_mut(name) {
                Some(p) => {
                    p.used = true;
                    out.push_str(&p.value);
                }
                None => {
                    return Err(err(
                        loc,
                        format!(
                            "undefined parameter '${name}' (declare <default name=\"{name}\" \
                             value=\"...\"/> or pass -D {name}=...)"
                        ),
                    ));
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn convert(
        &mut self,
        ctx: &FileCtx<'_>,
        node: roxmltree::Node<'_, '_>,
        depth: usize,
    ) -> Result<Converted> {
        let tag = node.tag_name().name().to_string();
        let loc = ctx.loc(node.range().start);
        if depth >= MAX_ELEMENT_DEPTH {
            return Err(err(
                &loc,
                format!("elements nested more than {MAX_ELEMENT_DEPTH} deep (<{tag}>)"),
            ));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let aloc = ctx.loc(a.range().start);
            let value = if tag == "default" {
                a.value().to_string()
            } else {
                self.substitute(a.value(), &aloc)?
            };
            attrs.push(Attr {
                name: a.name().to_string(),
                value,
                loc: aloc,
            });
        }
        let elem = Elem {
            tag,
            attrs,
            children: Vec::new(),
            loc,
            dir: ctx.dir.clone(),
        };
        match elem.tag.as_str() {
            "default" => {
                let (Some(name), Some(value)) = (elem.value("name"), elem.value("value")) else {
                    return Err(err(
                        &elem.loc,
                        "<default> needs both a 'name' and a 'value' attribute",
                    ));
                };
                if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(err(
                        &elem.loc_of("name"),
                        format!("invalid parameter name '{name}' (letters, digits and '_')"),
                    ));
                }
                self.params.entry(name.to_string()).or_insert(Param {
                    value: value.to_string(),
                    from_cli: false,
                    used: false,
                });
                return Ok(Converted::None);
            }
            "path" => {
                let value = elem.value("value").unwrap_or("");
                let dir = ctx.dir.join(value);
                if value.is_empty() || !dir.is_dir() {
                    self.warnings.push(Warning {
                        loc: elem.loc.clone(),
                        message: format!("<path value=\"{value}\">: folder not found, ignored"),
                    });
                } else {
                    self.search_dirs.push(dir);
                }
                return Ok(Converted::None);
            }
            "include" => {
                let Some(filename) = elem.value("filename") else {
                    return Err(err(&elem.loc, "<include> needs a 'filename' attribute"));
                };
                let path = resolve_file(filename, ctx.dir.as_path(), &self.search_dirs)
                    .ok_or_else(|| {
                        err(
                            &elem.loc_of("filename"),
                            format!("included file '{filename}' not found"),
                        )
                    })?;
                let root = self.read_file(&path, &elem.loc)?;
                return Ok(if root.tag == "scene" {
                    Converted::Many(root.children)
                } else {
                    Converted::One(root)
                });
            }
            _ => {}
        }
        let mut elem = elem;
        for child in node.children() {
            if child.is_element() {
                match self.convert(ctx, child, depth + 1)? {
                    Converted::One(e) => elem.children.push(e),
                    Converted::Many(v) => elem.children.extend(v),
                    Converted::None => {}
                }
            } else if child.is_text() {
                let t = child.text().unwrap_or("").trim();
                if !t.is_empty() {
                    let shown: String = t.chars().take(30).collect();
                    return Err(err(
                        &ctx.loc(child.range().start),
                        format!("unexpected text '{shown}' inside <{}>", elem.tag),
                    ));
                }
            }
        }
        Ok(Converted::One(elem))
    }
}

enum Converted {
    One(Elem),
    Many(Vec<Elem>),
    None,
}

struct FileCtx<'a> {
    index: TextIndex<'a>,
    file: &'a Arc<PathBuf>,
    dir: &'a Arc<PathBuf>,
}

impl FileCtx<'_> {
    fn loc(&self, pos: usize) -> Loc {
        let (line, col) = self.index.pos(pos);
        Loc::new(self.file, line, col)
    }
}

/// Resolve a relative file name: next to the referring file, then in the search folders.
pub fn resolve_file(name: &str, dir: &Path, search_dirs: &[PathBuf]) -> Option<PathBuf> {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.is_file().then(|| p.to_path_buf());
    }
    std::iter::once(dir)
        .chain(search_dirs.iter().map(PathBuf::as_path))
        .map(|d| d.join(p))
        .find(|c| c.is_file())
}

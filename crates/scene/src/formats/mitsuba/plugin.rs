//! Stage 2b: one plugin element (`<bsdf type="..">` ...) split into its properties and its
//! child objects, with `<ref>`s resolved through the document's id table.

use std::collections::HashMap;

use super::props::{Props, parse_property, snake_case};
use super::tree::{Elem, err};
use crate::{Loc, Result, Warning};

/// Tags that create objects (as opposed to properties).
pub const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "texture",
    "emitter",
    "shape",
    "mesh",
    "sensor",
    "camera",
    "film",
    "rfilter",
    "sampler",
    "integrator",
    "medium",
    "phase",
    "volume",
    "scene",
];

/// A child object, inline or through `<ref id>`.
pub struct Child<'s> {
    /// The `name` under which the parent receives it (`reflectance`, `bsdf`...), snake_case.
    pub name: Option<String>,
    /// The object's element (the referenced one for a `<ref>`).
    pub elem: &'s Elem,
    /// Where the child appears in the parent (the `<ref>` itself for references).
    pub loc: Loc,
}

impl Child<'_> {
    /// Key for instancing an object once: its id when it has one.
    pub fn id(&self) -> Option<&str> {
        self.elem.value("id")
    }
}

pub struct Plugin<'s> {
    pub elem: &'s Elem,
    /// The `type` attribute ("" for `<scene>`).
    pub ty: String,
    pub props: Props,
    pub children: Vec<Child<'s>>,
}

impl<'s> Plugin<'s> {
    pub fn new(
        elem: &'s Elem,
        ids: &HashMap<String, &'s Elem>,
        warnings: &mut Vec<Warning>,
    ) -> Result<Self> {
        let ty = elem.value("type").unwrap_or("").trim().to_string();
        let mut props = Vec::new();
        let mut seen: HashMap<String, Loc> = HashMap::new();
        let mut children = Vec::new();
        for c in &elem.children {
            if let Some(p) = parse_property(c, warnings)? {
                // As Mitsuba 3: a property given twice is an error, not a silent override.
                if let Some(first) = seen.insert(p.name.clone(), p.loc.clone()) {
                    return Err(err(
                        &p.loc,
                        format!(
                            "parameter '{}' of <{} type=\"{ty}\"> is given twice (first at {})",
                            p.name, elem.tag, first
                        ),
                    ));
                }
                props.push(p);
                continue;
            }
            if c.tag == "ref" {
                let id = c
                    .value("id")
                    .ok_or_else(|| err(&c.loc, "<ref> needs an 'id' attribute"))?;
                let target = ids.get(id).ok_or_else(|| {
                    err(
                        &c.loc_of("id"),
                        format!("<ref id=\"{id}\">: no object has this id"),
                    )
                })?;
                children.push(Child {
                    name: c.value("name").map(snake_case),
                    elem: target,
                    loc: c.loc.clone(),
                });
            } else if OBJECT_TAGS.contains(&c.tag.as_str()) {
                children.push(Child {
                    name: c.value("name").map(snake_case),
                    elem: c,
                    loc: c.loc.clone(),
                });
            } else {
                return Err(err(
                    &c.loc,
                    format!("unknown tag <{}> inside <{}>", c.tag, elem.tag),
                ));
            }
        }
        Ok(Plugin {
            elem,
            ty,
            props: Props { props },
            children,
        })
    }

    pub fn loc(&self) -> &Loc {
        &self.elem.loc
    }

    /// Children with the given tag(s).
    pub fn children_with<'a>(&'a self, tags: &'a [&'a str]) -> impl Iterator<Item = &'a Child<'s>> {
        self.children
            .iter()
            .filter(move |c| tags.contains(&c.elem.tag.as_str()))
    }

    /// The last child named `name` (textures given for a parameter).
    pub fn named_child(&self, name: &str) -> Option<&Child<'s>> {
        self.children
            .iter()
            .rev()
            .find(|c| c.name.as_deref() == Some(name))
    }
}

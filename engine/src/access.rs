//! Which words of its item a pass may read and may write, from naga's IR: the access chains
//! (`AccessIndex`, `Access`) that start at the pass's item pointer, the loads and stores
//! through them, and the calls that hand the pointer (or a pointer into it) on to other
//! functions, analysed in turn. Words are numbered as [`crate::reflect::flatten`] orders
//! them. A dynamic index counts as every element; a whole-struct load or store counts as
//! every word under it.
//!
//! In a valid module a function-space pointer to an item's data (32-bit scalars, vectors,
//! matrices, fixed arrays and structs of them) is used only by access chains, loads, stores
//! and call arguments, which is all this analysis follows.

use naga::{Expression, Function, Handle, Literal, Module, Statement, TypeInner};
use std::collections::{BTreeSet, HashMap};

/// The words of an item a function may read and may write through one pointer argument.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Access {
    /// Words it may read.
    pub read: BTreeSet<u32>,
    /// Words it may write.
    pub write: BTreeSet<u32>,
}

impl Access {
    /// Adds `other`'s words, each moved by `offset`.
    fn absorb(&mut self, other: &Access, offset: u32) {
        self.read.extend(other.read.iter().map(|w| w + offset));
        self.write.extend(other.write.iter().map(|w| w + offset));
    }

    /// Adds `other`'s words.
    pub fn union(&mut self, other: &Access) {
        self.absorb(other, 0);
    }
}

/// What a pointer derived from the argument points at.
#[derive(Debug, Clone, Copy)]
enum Shape {
    /// A value of a module type.
    Type(Handle<naga::Type>),
    /// A vector's component.
    Scalar,
    /// A matrix's column of this many rows.
    Column(u32),
}

/// A pointer into the argument's pointee: its shape at each of these word offsets.
#[derive(Debug, Clone)]
struct Pointer {
    shape: Shape,
    offsets: Vec<u32>,
}

/// Number of 32-bit words of a type, as [`crate::reflect::flatten`] counts them (types an
/// item cannot hold count as one word).
pub fn word_count(module: &Module, ty: Handle<naga::Type>) -> u32 {
    match &module.types[ty].inner {
        TypeInner::Vector { size, .. } => *size as u32,
        TypeInner::Matrix { columns, rows, .. } => *columns as u32 * *rows as u32,
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => n.get() * word_count(module, *base),
        TypeInner::Struct { members, .. } => members.iter().map(|m| word_count(module, m.ty)).sum(),
        _ => 1,
    }
}

/// Analyses functions of one module, remembering each (function, argument) it has seen.
pub struct Analysis<'m> {
    module: &'m Module,
    memo: HashMap<(Handle<Function>, u32), Access>,
}

impl<'m> Analysis<'m> {
    /// An analysis of `module`.
    pub fn new(module: &'m Module) -> Self {
        Analysis {
            module,
            memo: HashMap::new(),
        }
    }

    /// The words of the pointee of argument 0 that the function called `name` may read and
    /// write; `None` if there is no such function or its argument 0 is not a pointer.
    pub fn pass(&mut self, name: &str) -> Option<Access> {
        let (f, func) = self
            .module
            .functions
            .iter()
            .find(|(_, f)| f.name.as_deref() == Some(name))?;
        let arg = func.arguments.first()?;
        matches!(self.module.types[arg.ty].inner, TypeInner::Pointer { .. }).then(|| self.argument(f, 0))
    }

    /// The words of the pointee of argument `arg` of `f` that `f` may read and write.
    fn argument(&mut self, f: Handle<Function>, arg: u32) -> Access {
        if let Some(a) = self.memo.get(&(f, arg)) {
            return a.clone();
        }
        let func = &self.module.functions[f];
        let pointers = self.pointers(func, arg);
        let mut access = Access::default();
        for (_, e) in func.expressions.iter() {
            if let Expression::Load { pointer } = e
                && let Some(p) = &pointers[pointer.index()]
            {
                access.read.extend(self.words(p));
            }
        }
        self.statements(&func.body, &pointers, &mut access);
        self.memo.insert((f, arg), access.clone());
        access
    }

    /// For every expression of `func`, the pointer it is when it derives from argument `arg`.
    fn pointers(&self, func: &Function, arg: u32) -> Vec<Option<Pointer>> {
        let mut out: Vec<Option<Pointer>> = Vec::with_capacity(func.expressions.len());
        for (_, e) in func.expressions.iter() {
            let p = match *e {
                Expression::FunctionArgument(i) if i == arg => {
                    match self.module.types[func.arguments[i as usize].ty].inner {
                        TypeInner::Pointer { base, .. } => Some(Pointer {
                            shape: Shape::Type(base),
                            offsets: vec![0],
                        }),
                        _ => None,
                    }
                }
                Expression::AccessIndex { base, index } => {
                    out[base.index()].as_ref().map(|p| self.element(p, Some(index)))
                }
                Expression::Access { base, index } => out[base.index()]
                    .as_ref()
                    .map(|p| self.element(p, constant_index(&func.expressions[index]))),
                _ => None,
            };
            out.push(p);
        }
        out
    }

    /// The element `index` of what `p` points at (every element when `None`).
    fn element(&self, p: &Pointer, index: Option<u32>) -> Pointer {
        let (shape, stride, count) = match p.shape {
            Shape::Scalar => (Shape::Scalar, 0, 1),
            Shape::Column(rows) => (Shape::Scalar, 1, rows),
            Shape::Type(ty) => match &self.module.types[ty].inner {
                TypeInner::Vector { size, .. } => (Shape::Scalar, 1, *size as u32),
                TypeInner::Matrix { columns, rows, .. } => (Shape::Column(*rows as u32), *rows as u32, *columns as u32),
                TypeInner::Array {
                    base,
                    size: naga::ArraySize::Constant(n),
                    ..
                } => (Shape::Type(*base), word_count(self.module, *base), n.get()),
                TypeInner::Struct { members, .. } => {
                    // A struct is only indexed by a known member.
                    let m = index.unwrap_or(0) as usize;
                    let before: u32 = members[..m].iter().map(|m| word_count(self.module, m.ty)).sum();
                    return Pointer {
                        shape: Shape::Type(members[m].ty),
                        offsets: p.offsets.iter().map(|o| o + before).collect(),
                    };
                }
                // Not understood: the whole of it, as a sub-tree nothing indexes further.
                _ => return p.clone(),
            },
        };
        let picks: Vec<u32> = match index {
            Some(i) => vec![i],
            None => (0..count).collect(),
        };
        Pointer {
            shape,
            offsets: p
                .offsets
                .iter()
                .flat_map(|o| picks.iter().map(move |i| o + i * stride))
                .collect(),
        }
    }

    /// Every word `p` may point at.
    fn words(&self, p: &Pointer) -> impl Iterator<Item = u32> + use<> {
        let n = match p.shape {
            Shape::Scalar => 1,
            Shape::Column(rows) => rows,
            Shape::Type(ty) => word_count(self.module, ty),
        };
        p.offsets.clone().into_iter().flat_map(move |o| o..o + n)
    }

    /// Stores and calls of `block` through the pointers.
    fn statements(&mut self, block: &naga::Block, pointers: &[Option<Pointer>], access: &mut Access) {
        for s in block.iter() {
            match s {
                Statement::Block(b) => self.statements(b, pointers, access),
                Statement::If { accept, reject, .. } => {
                    self.statements(accept, pointers, access);
                    self.statements(reject, pointers, access);
                }
                Statement::Switch { cases, .. } => {
                    for c in cases {
                        self.statements(&c.body, pointers, access);
                    }
                }
                Statement::Loop { body, continuing, .. } => {
                    self.statements(body, pointers, access);
                    self.statements(continuing, pointers, access);
                }
                Statement::Store { pointer, .. } => {
                    if let Some(p) = &pointers[pointer.index()] {
                        access.write.extend(self.words(p));
                    }
                }
                Statement::Call {
                    function, arguments, ..
                } => {
                    for (j, a) in arguments.iter().enumerate() {
                        if let Some(p) = &pointers[a.index()] {
                            let callee = self.argument(*function, j as u32);
                            for &o in &p.offsets {
                                access.absorb(&callee, o);
                            }
                        }
                    }
                }
                _ => {}
            }
        }
    }
}

/// The value of an index that is a literal.
fn constant_index(e: &Expression) -> Option<u32> {
    match *e {
        Expression::Literal(Literal::U32(i)) => Some(i),
        Expression::Literal(Literal::I32(i)) => u32::try_from(i).ok(),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ITEM: &str = "
        struct V { p: vec3<f32>, n: u32 }
        struct Item { a: vec2<f32>, count: u32, vs: array<V, 3>, m: mat2x2<f32>, last: f32 }
    ";
    // Words: a 0-1, count 2, vs 3-14 (V = 4 words), m 15-18, last 19.

    fn analyse(body: &str, name: &str) -> Access {
        let m = naga::front::wgsl::parse_str(&format!("{ITEM}\n{body}")).unwrap();
        assert_eq!(word_count(&m, crate::reflect::find_type(&m, "Item").unwrap()), 20);
        Analysis::new(&m).pass(name).unwrap()
    }

    fn set(words: impl IntoIterator<Item = u32>) -> BTreeSet<u32> {
        words.into_iter().collect()
    }

    #[test]
    fn fields_read_and_written() {
        let a = analyse(
            "fn f(it: ptr<function, Item>) -> bool { (*it).last = (*it).a.y + 1.0; return (*it).count > 0u; }",
            "f",
        );
        assert_eq!(a.read, set([1, 2]));
        assert_eq!(a.write, set([19]));
    }

    #[test]
    fn through_helper_functions_and_sub_pointers() {
        let a = analyse(
            "fn touch(v: ptr<function, V>) { (*v).n = 1u; }
             fn read_m(it: ptr<function, Item>) -> f32 { return (*it).m[1].x; }
             fn f(it: ptr<function, Item>) -> bool { touch(&(*it).vs[2]); return read_m(it) > 0.0; }",
            "f",
        );
        assert_eq!(a.read, set([17]));
        assert_eq!(a.write, set([14]));
    }

    #[test]
    fn a_dynamic_index_counts_as_every_element() {
        let a = analyse(
            "fn f(it: ptr<function, Item>) -> bool { (*it).vs[(*it).count].p.y = 2.0; return true; }",
            "f",
        );
        assert_eq!(a.read, set([2]));
        assert_eq!(a.write, set([4, 8, 12]));
    }

    #[test]
    fn whole_copies_count_as_every_word() {
        let a = analyse(
            "fn f(it: ptr<function, Item>) -> bool { var c = *it; c.last = 1.0; *it = c; return true; }",
            "f",
        );
        assert_eq!(a.read, set(0..20));
        assert_eq!(a.write, set(0..20));
        let v = analyse(
            "fn f(it: ptr<function, Item>) -> bool { let v = (*it).vs[1]; (*it).a = vec2<f32>(v.p.x); return true; }",
            "f",
        );
        assert_eq!(v.read, set(7..11));
        assert_eq!(v.write, set([0, 1]));
    }

    #[test]
    fn only_pointer_passes_are_analysed() {
        let m = naga::front::wgsl::parse_str(&format!("{ITEM}\nfn g(x: u32) -> bool {{ return x > 0u; }}")).unwrap();
        assert!(Analysis::new(&m).pass("g").is_none());
        assert!(Analysis::new(&m).pass("missing").is_none());
    }
}

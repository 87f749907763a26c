//! Typed indices of the things the stages hand to one another: passes, operators, chains,
//! phases, kernels, compaction boundaries, resources and streams. Each indexes its own table,
//! so a chain index cannot be used to look up a pass: the module that defines an item says
//! which id indexes it (`indexes!`), so that this leaf module names none of them. Resources
//! and streams are interned at load; their ids have no `Display`, so that what a report or an
//! error prints of them is their name, never their number.

use std::fmt;

macro_rules! typed_id {
    ($(#[$doc:meta])* $name:ident, named) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(pub usize);
    };
    ($(#[$doc:meta])* $name:ident) => {
        typed_id!($(#[$doc])* $name, named);

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{}", self.0)
            }
        }
    };
}

/// Lets an id index the `Vec` of the items it names (`indexes!(PassId => Pass)`), written by
/// the module that defines the item, so that no other id indexes it.
macro_rules! indexes {
    ($name:ty => $item:ty) => {
        impl std::ops::Index<$name> for Vec<$item> {
            type Output = $item;
            fn index(&self, id: $name) -> &$item {
                &self[id.0]
            }
        }

        impl std::ops::IndexMut<$name> for Vec<$item> {
            fn index_mut(&mut self, id: $name) -> &mut $item {
                &mut self[id.0]
            }
        }
    };
}
pub(crate) use indexes;

typed_id!(
    /// A live pass: an index into [`crate::Graph::passes`].
    PassId
);
typed_id!(
    /// A live operator: an index into [`crate::Graph::ops`].
    OpId
);
typed_id!(
    /// An item chain: an index into [`crate::Graph::chains`].
    ChainId
);
typed_id!(
    /// A phase: an index into [`crate::Graph::phases`].
    PhaseId
);
typed_id!(
    /// A kernel of a layout: an index into [`crate::Plan::kernels`].
    KernelId
);
typed_id!(
    /// A compaction boundary: an index into [`crate::Plan::boundaries`].
    BoundaryId
);
typed_id!(
    /// A resource of the live graph: an index into [`crate::Graph::resources`], interned in
    /// name order where the live graph is built.
    ResourceId,
    named
);
typed_id!(
    /// A stream: an index into [`crate::Graph::streams`], interned in name order at load.
    StreamId,
    named
);

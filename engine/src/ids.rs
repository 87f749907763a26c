//! Typed indices of the things the stages hand to one another: passes, operators, chains,
//! phases, kernels and compaction boundaries. Each indexes its own table, so a chain index
//! cannot be used to look up a pass.

use std::fmt;

macro_rules! typed_id {
    ($(#[$doc:meta])* $name:ident indexes $item:ty) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(pub usize);

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{}", self.0)
            }
        }

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

typed_id!(
    /// A live pass: an index into [`crate::Graph::passes`].
    PassId indexes crate::graph::Pass
);
typed_id!(
    /// A live operator: an index into [`crate::Graph::ops`].
    OpId indexes crate::operator::Operator
);
typed_id!(
    /// An item chain: an index into [`crate::Graph::chains`].
    ChainId indexes crate::graph::Chain
);
typed_id!(
    /// A phase: an index into [`crate::Graph::phases`].
    PhaseId indexes crate::graph::Phase
);
typed_id!(
    /// A kernel of a layout: an index into [`crate::Plan::kernels`].
    KernelId indexes crate::plan::KernelPlan
);
typed_id!(
    /// A compaction boundary: an index into [`crate::Plan::boundaries`].
    BoundaryId indexes crate::plan::Boundary
);

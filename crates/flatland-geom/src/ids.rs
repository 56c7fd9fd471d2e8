//! The two indices the public API hands out: an edge of a scene ([`EdgeId`]) and a parent
//! surface edge's place in parameter order ([`SurfaceRank`]). Each is a `u32` in its own type,
//! so one cannot be passed where the other is meant; both cost what a `u32` costs (`Copy`, no
//! niche: `Option` of either is 8 bytes, which keeps the kernel's per-parent record packed).

use std::fmt;

/// An edge of a [`Scene`](crate::Scene): its index into [`Scene::edges`](crate::Scene::edges)
/// (of a subdivided edge, one piece). Meaningful only for the scene it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct EdgeId(u32);

/// A parent surface edge's rank: its place among the parent surface edges in parameter (file)
/// order, `0..Kernel::surface_parents()`; pieces of one subdivided edge share it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SurfaceRank(u32);

macro_rules! index_type {
    ($name:ident) => {
        impl $name {
            /// The id of index `index`.
            ///
            /// # Panics
            /// If `index` does not fit in a `u32` (no scene in memory has that many edges).
            #[must_use]
            #[inline]
            pub fn new(index: usize) -> $name {
                $name(u32::try_from(index).expect(concat!(stringify!($name), " fits in a u32")))
            }

            /// The index, for indexing a slice.
            #[must_use]
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }
        }

        impl fmt::Display for $name {
            /// The bare index, as the CLI prints it.
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.0.fmt(f)
            }
        }
    };
}

index_type!(EdgeId);
index_type!(SurfaceRank);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_their_index_and_print_as_it() {
        let (e, r) = (EdgeId::new(7), SurfaceRank::new(3));
        assert_eq!((e.index(), r.index()), (7, 3));
        assert_eq!(
            (e.to_string(), format!("{r}")),
            ("7".to_owned(), "3".to_owned())
        );
        assert!(EdgeId::new(2) < EdgeId::new(10), "ordered as their indices");
        assert_eq!(size_of::<Option<SurfaceRank>>(), 8);
    }

    #[test]
    #[should_panic(expected = "fits in a u32")]
    fn an_index_past_u32_is_refused() {
        let _ = EdgeId::new(1 << 32);
    }
}

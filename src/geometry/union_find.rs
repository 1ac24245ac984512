//! Disjoint sets over `0..n`: connected components of triangles, patches and
//! node groups (mesh checks, the hex stage's feature sheets).

/// Disjoint sets with path halving; a union keeps the smaller root, so the sets'
/// representatives do not depend on the order of a union's arguments.
#[derive(Debug, Clone)]
pub(crate) struct UnionFind(Vec<u32>);

impl UnionFind {
    /// `n` singletons.
    pub(crate) fn new(n: usize) -> Self {
        UnionFind((0..n as u32).collect())
    }

    /// The representative of `x`'s set.
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }

    /// Join the sets of `a` and `b`; false when they were one set already.
    pub(crate) fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        self.0[hi as usize] = lo;
        true
    }

    /// Every element's set as a number in `0..count`, numbered in the order of
    /// the sets' first elements; and the count.
    pub(crate) fn labels(&mut self) -> (Vec<u32>, usize) {
        let n = self.0.len();
        let mut id = vec![u32::MAX; n];
        let mut count = 0u32;
        let out = (0..n as u32)
            .map(|x| {
                let r = self.find(x) as usize;
                if id[r] == u32::MAX {
                    id[r] = count;
                    count += 1;
                }
                id[r]
            })
            .collect();
        (out, count as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_are_numbered_by_their_first_element() {
        let mut uf = UnionFind::new(6);
        assert!(uf.union(4, 1));
        assert!(uf.union(5, 3));
        assert!(uf.union(3, 1));
        assert!(!uf.union(5, 4));
        assert_eq!(uf.find(5), 1);
        assert_eq!(uf.labels(), (vec![0, 1, 2, 1, 1, 1], 3));
    }
}

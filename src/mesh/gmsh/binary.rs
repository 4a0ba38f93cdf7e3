//! A direct reader of the `$Nodes` and `$Elements` sections of a well-formed binary MSH 4.1
//! file: the bulk of a fine mesh (at L5, 5.5 MB: 14 ms through `mshio`'s parser, which
//! allocates a vector per element; ≈ 3 ms here).
//!
//! It reads only what it can read completely: little-endian files with 8-byte sizes (what
//! gmsh writes on 64-bit machines), nodes without parametric
//! coordinates, element blocks of 6-node triangles on surfaces, 3-node lines on curves and
//! points (type 15, skipped), the `$Nodes` section followed by the `$Elements` section and
//! nothing but white space after it. On anything else it returns `None`, and the caller reads
//! the file through `mshio` instead, which reports what is wrong with it; the two readers give
//! the same mesh (`super::tests::both_readers_give_the_same_mesh`).

/// The two sections as read: nodes in file order with their tags, and the element blocks.
pub(super) struct Body {
    pub nodes: Vec<[f64; 2]>,
    pub node_tags: Vec<u64>,
    pub blocks: Vec<Block>,
}

/// One element block: its entity, gmsh element type (8 or 9) and its elements' tags and node
/// tags (3 or 6 per element, one element after the other).
pub(super) struct Block {
    pub dim: i32,
    pub entity_tag: i32,
    pub kind: u8,
    pub tags: Vec<u64>,
    pub nodes: Vec<u64>,
}

impl Block {
    /// The block's elements: (tag, node tags).
    pub fn elements(&self) -> impl Iterator<Item = (u64, &[u64])> {
        let per = if self.kind == 9 { 6 } else { 3 };
        self.tags.iter().copied().zip(self.nodes.chunks_exact(per))
    }
}

/// A cursor over the bytes of the sections.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.bytes.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }

    fn int(&mut self) -> Option<i32> {
        Some(i32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }

    fn size(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    /// `n` sizes, appended to `out`.
    fn sizes(&mut self, n: usize, out: &mut Vec<u64>) -> Option<()> {
        let s = self.take(n.checked_mul(8)?)?;
        out.extend(
            s.chunks_exact(8)
                .map(|w| u64::from_le_bytes(w.try_into().expect("8 bytes"))),
        );
        Some(())
    }

    /// Skips white space, then expects the line `word`: the word and its line end (binary
    /// data may follow, whose first byte may look like white space).
    fn word(&mut self, word: &[u8]) -> Option<()> {
        self.space();
        let rest = &self.bytes[self.pos..];
        let end = if rest.get(word.len()..)?.starts_with(b"\r\n") {
            2
        } else if rest.get(word.len()) == Some(&b'\n') {
            1
        } else {
            return None;
        };
        if !rest.starts_with(word) {
            return None;
        }
        self.pos += word.len() + end;
        Some(())
    }

    fn space(&mut self) {
        while self
            .bytes
            .get(self.pos)
            .is_some_and(u8::is_ascii_whitespace)
        {
            self.pos += 1;
        }
    }
}

/// The position of the line `$Nodes` in `bytes` (the start of the node section), if any.
pub(super) fn nodes_start(bytes: &[u8]) -> Option<usize> {
    let mut from = 0;
    while let Some(k) = bytes[from..].windows(7).position(|w| w == b"\n$Nodes") {
        let at = from + k + 1;
        if bytes.get(at + 6).is_none_or(|&b| b == b'\n' || b == b'\r') {
            return Some(at);
        }
        from = at;
    }
    None
}

/// Reads the node and element sections from `body` (the file from its `$Nodes` line on) of a
/// binary file with `size_t`-byte sizes; `None` when they are not as this reader expects.
pub(super) fn read(body: &[u8], size_t: usize) -> Option<Body> {
    if size_t != 8 {
        return None;
    }
    let mut c = Cursor {
        bytes: body,
        pos: 0,
    };
    c.word(b"$Nodes")?;
    let (nodes, node_tags) = read_nodes(&mut c)?;
    c.word(b"$EndNodes")?;
    c.word(b"$Elements")?;
    let blocks = read_elements(&mut c)?;
    c.word(b"$EndElements")?;
    c.space();
    (c.pos == body.len()).then_some(Body {
        nodes,
        node_tags,
        blocks,
    })
}

fn read_nodes(c: &mut Cursor) -> Option<(Vec<[f64; 2]>, Vec<u64>)> {
    let nblocks = c.size()?;
    let total = usize::try_from(c.size()?).ok()?;
    let (_min, _max) = (c.size()?, c.size()?);
    // Each node takes at least 24 bytes: a count beyond the file is a lie.
    if total > c.bytes.len() / 24 {
        return None;
    }
    let mut nodes = Vec::with_capacity(total);
    let mut tags = Vec::with_capacity(total);
    for _ in 0..nblocks {
        let (_dim, _entity, parametric) = (c.int()?, c.int()?, c.int()?);
        let n = usize::try_from(c.size()?).ok()?;
        if parametric != 0 || n > total - tags.len() {
            return None;
        }
        c.sizes(n, &mut tags)?;
        let xyz = c.take(n.checked_mul(24)?)?;
        nodes.extend(xyz.chunks_exact(24).map(|p| {
            let f = |k: usize| f64::from_le_bytes(p[8 * k..8 * k + 8].try_into().expect("8"));
            [f(0), f(1)]
        }));
    }
    (tags.len() == total).then_some((nodes, tags))
}

fn read_elements(c: &mut Cursor) -> Option<Vec<Block>> {
    let nblocks = c.size()?;
    let total = usize::try_from(c.size()?).ok()?;
    let (_min, _max) = (c.size()?, c.size()?);
    if total > c.bytes.len() / 16 {
        return None;
    }
    let mut blocks = Vec::new();
    let mut seen = 0usize;
    for _ in 0..nblocks {
        let (dim, entity_tag, kind) = (c.int()?, c.int()?, c.int()?);
        let n = usize::try_from(c.size()?).ok()?;
        let per = match (kind, dim) {
            (15, 0) => 1,
            (8, 1) => 3,
            (9, 2) => 6,
            _ => return None,
        };
        if n > total - seen {
            return None;
        }
        seen += n;
        let words = c.take(n.checked_mul(8 * (per + 1))?)?;
        if kind == 15 {
            continue;
        }
        let word = |w: &[u8]| u64::from_le_bytes(w.try_into().expect("8 bytes"));
        let mut block = Block {
            dim,
            entity_tag,
            kind: kind as u8,
            tags: Vec::with_capacity(n),
            nodes: Vec::with_capacity(n * per),
        };
        for e in words.chunks_exact(8 * (per + 1)) {
            block.tags.push(word(&e[..8]));
            block.nodes.extend(e[8..].chunks_exact(8).map(word));
        }
        blocks.push(block);
    }
    (seen == total).then_some(blocks)
}

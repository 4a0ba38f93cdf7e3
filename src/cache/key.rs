//! The key of a model: a hash of everything its linear algebra depends on.

use super::format::FORMAT;
use super::hash::{Xxh64, xxh64};
use crate::case::Case;

/// The 128-bit key of a cache entry (two XXH64 of the key material with different seeds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key(pub [u64; 2]);

impl Key {
    pub fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.0[0], self.0[1])
    }
}

/// The key material: length-prefixed fields, floats by their bits, hashed as it comes (two
/// seeds: 128 bits) rather than gathered first (the mesh file is most of it).
struct KeyBuilder([Xxh64; 2]);

impl KeyBuilder {
    fn new() -> KeyBuilder {
        KeyBuilder([Xxh64::new(0), Xxh64::new(0x005e_ed0f_ca11)])
    }
    fn raw(&mut self, b: &[u8]) {
        for h in &mut self.0 {
            h.update(b);
        }
    }
    fn bytes(&mut self, b: &[u8]) {
        self.raw(&(b.len() as u64).to_le_bytes());
        self.raw(b);
    }
    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.raw(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn opt_f64(&mut self, v: Option<f64>) {
        match v {
            Some(x) => {
                self.u64(1);
                self.f64(x);
            }
            None => self.u64(0),
        }
    }
    fn finish(&self) -> Key {
        Key([self.0[0].finish(), self.0[1].finish()])
    }
}

/// The identity of the running program's code: XXH64 of its executable file, read once.
/// Any rebuild that changes the machine code (the source, a dependency such as faer, the
/// compiler or its flags) changes it, so an entry is never used by other code than wrote it.
pub fn build_id() -> Result<u64, String> {
    static ID: std::sync::OnceLock<Result<u64, String>> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe().map_err(|e| format!("cannot locate the program: {e}"))?;
        let bytes = std::fs::read(&exe)
            .map_err(|e| format!("cannot read the program {}: {e}", exe.display()))?;
        Ok(xxh64(&bytes, 0))
    })
    .clone()
}

/// The key of a model's linear algebra: the cache format, the program version and build
/// ([`build_id`]), the ordering policy, the bytes of the mesh file, the bodies (group, E, ν) in
/// order, the supports (group, ux, uy) in order, the pilot's group, and the contact pair
/// (slave, master, the candidate gap in use, the normal kind). Nothing else changes `K`, the
/// constraint rows or the loads of the prescribed displacements: not the friction law, the
/// contact method, the tractions, the stages or the output, nor the number of threads (the
/// factorisation is bit-identical with any). `gap` is the candidate gap the pair was built
/// with (`None` without contact).
pub fn model_key(case: &Case, mesh_bytes: &[u8], gap: Option<f64>) -> Result<Key, String> {
    let mut k = KeyBuilder::new();
    k.str("stickslip model cache");
    k.u64(FORMAT as u64);
    k.str(env!("CARGO_PKG_VERSION"));
    k.u64(build_id()?);
    k.str(crate::la::ordering::ordering_policy());
    k.bytes(mesh_bytes);
    k.u64(case.bodies.len() as u64);
    for b in &case.bodies {
        k.str(&b.group);
        k.f64(b.e);
        k.f64(b.nu);
    }
    k.u64(case.supports.len() as u64);
    for s in &case.supports {
        k.str(&s.group);
        k.opt_f64(s.ux);
        k.opt_f64(s.uy);
    }
    match &case.pilot {
        Some(p) => {
            k.u64(1);
            k.str(&p.group);
        }
        None => k.u64(0),
    }
    match &case.contact {
        Some(c) => {
            k.u64(1);
            k.str(&c.slave);
            k.str(&c.master);
            k.opt_f64(gap);
            k.str(match c.normal {
                crate::case::NormalKind::Common => "common",
                crate::case::NormalKind::Local => "local",
            });
        }
        None => k.u64(0),
    }
    Ok(k.finish())
}

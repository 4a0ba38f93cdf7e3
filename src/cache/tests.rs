use super::format::CHUNK;
use super::*;

/// The bytes of `w` as written (its own memory where it can) and converted word by word.
fn both_ways(w: &Words) -> (Vec<u8>, Vec<u8>) {
    let (mut direct, mut converted) = (Vec::new(), Vec::new());
    w.for_each_chunk(|b| {
        direct.extend_from_slice(b);
        Ok(())
    })
    .unwrap();
    w.for_each_converted_chunk(|b| {
        converted.extend_from_slice(b);
        Ok(())
    })
    .unwrap();
    (direct, converted)
}

#[test]
fn the_bytes_of_words_are_their_little_endian_bytes() {
    let n = CHUNK / 8 + 5; // more than a chunk
    let f: Vec<f64> = (0..n).map(|i| (i as f64).sqrt() - 3.5).collect();
    let u: Vec<usize> = (0..n).map(|i| i * 2_654_435_761).collect();
    let shared = std::sync::Arc::new(crate::la::FactorValues::Owned(f.clone()));
    for w in [
        Words::F64(f.clone()),
        Words::U64(u.iter().map(|&x| x as u64).collect()),
        Words::Usize(u.clone()),
        Words::Shared(shared.clone()),
    ] {
        assert_eq!(w.len(), n);
        let (direct, converted) = both_ways(&w);
        assert_eq!(direct.len(), 8 * n);
        assert!(direct == converted);
    }
    // A dense matrix's columns, all of them and the lower triangle (more than a chunk).
    let m = 1100;
    let a = std::sync::Arc::new(faer::Mat::from_fn(m, m, |i, j| i as f64 - 0.5 * j as f64));
    for (w, lower) in [
        (Words::all_columns(a.clone(), m), false),
        (Words::lower_columns(a.clone(), m), true),
    ] {
        let expected: Vec<u8> = (0..m)
            .flat_map(|j| (if lower { j } else { 0 }..m).map(move |i| (i, j)))
            .flat_map(|(i, j)| a[(i, j)].to_le_bytes())
            .collect();
        let (direct, converted) = both_ways(&w);
        assert_eq!(8 * w.len(), expected.len());
        assert!(direct == expected && converted == expected);
    }
}

#[test]
fn xxh64_reference_values() {
    assert_eq!(xxh64(b"", 0), 0xEF46_DB37_51D8_E999);
    assert_eq!(xxh64(b"a", 0), 0xD24E_C4F1_A98C_6E5B);
    assert_eq!(xxh64(b"abc", 0), 0x44BC_2CF5_AD77_0999);
    // Longer inputs (the 32-byte stripes), values from the `xxhash` Python package.
    let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
    assert_eq!(xxh64(&data, 42), 0xe7ca_5372_fc8e_a0a7);
    assert_eq!(xxh64(&data[..100], 0), 0xdad7_6c5e_3ed4_0107);
}

#[test]
fn xxh64_streaming_matches_one_shot() {
    let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
    for split in [0, 1, 7, 31, 32, 33, 100, 999, 1000] {
        let mut h = Xxh64::new(42);
        h.update(&data[..split]);
        h.update(&data[split..]);
        assert_eq!(h.finish(), xxh64(&data, 42), "split {split}");
    }
}

#[test]
fn sizes() {
    assert_eq!(parse_size("4G"), Some(4 << 30));
    assert_eq!(parse_size("500MiB"), Some(500 << 20));
    assert_eq!(parse_size("1024"), Some(1024));
    assert_eq!(parse_size("1.5k"), Some(1536));
    assert_eq!(parse_size("lots"), None);
}

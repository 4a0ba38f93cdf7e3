//! The `.vtu`/`.pvd` output reads back through vtkio with the documented arrays, and their
//! values are those of the solve (displacement of the pilot face, stress at the support).

mod common;
use common::{repo, stickslip};
use vtkio::model::{Attribute, DataSet, IOBuffer};

#[test]
fn vtu_holds_every_documented_array_with_finite_values() {
    let dir = common::tempdir("vtu");
    let t0 = std::time::Instant::now();
    let (code, _, err) = stickslip(&[
        "run",
        repo().join("cases/arc_hertz.json").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    let process_s = t0.elapsed().as_secs_f64();
    assert!(code == 0, "{err}");
    let pvd = std::fs::read_to_string(dir.join("arc_hertz.pvd")).unwrap();
    assert!(pvd.contains("file=\"arc_hertz_0001.vtu\""));
    let vtk = vtkio::Vtk::import(dir.join("arc_hertz_0001.vtu")).unwrap();
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    let piece = pieces[0].load_piece_data(None).unwrap();
    let npts = piece.num_points();
    let expect = [
        ("displacement", 3),
        ("stress_xx", 1),
        ("stress_yy", 1),
        ("stress_xy", 1),
        ("stress_zz", 1),
        ("von_mises", 1),
    ];
    for (name, ncomp) in expect {
        let arr = piece.data.point.iter().find_map(|a| match a {
            Attribute::DataArray(d) if d.name == name => Some(d),
            _ => None,
        });
        let arr = arr.unwrap_or_else(|| panic!("{name} missing"));
        let IOBuffer::F64(v) = &arr.data else {
            panic!("{name} not f64")
        };
        assert_eq!(v.len(), npts * ncomp, "{name}");
        assert!(
            v.iter().all(|x| x.is_finite()),
            "{name} has non-finite values"
        );
    }
    let body = piece
        .data
        .cell
        .iter()
        .any(|a| matches!(a, Attribute::DataArray(d) if d.name == "body_id"));
    assert!(body, "body_id missing");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    // Every phase is reported, and the phases (disjoint parts of the run) add up to no more
    // than the process took from the outside: a phase counted twice would exceed it.
    let phases = [
        "read",
        "assemble",
        "analyse",
        "factorise",
        "condense",
        "solve",
        "write",
    ];
    let sum: f64 = phases
        .iter()
        .map(|k| {
            let v = summary["timings_s"][*k].as_f64();
            assert!(v.is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {v:?}");
            v.unwrap()
        })
        .sum();
    println!("phases add up to {sum:.3} s of the process's {process_s:.3} s");
    assert!(
        sum <= process_s,
        "phases {sum} s exceed the process's {process_s} s"
    );
    assert!(summary["peak_memory_mib"].as_f64().unwrap() > 0.0);
}

/// Counts, indices and status codes in the CSV files are integers, not `4.0e0`.
#[test]
fn csv_counts_are_integers() {
    let dir = common::tempdir("csv-int");
    let (code, _, err) = stickslip(&[
        "run",
        repo().join("cases/vm272_cm.json").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(code == 0, "{err}");
    let check = |file: &str, cols: &[&str]| {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        for line in lines {
            let v: Vec<&str> = line.split(',').collect();
            for c in cols {
                let k = header.iter().position(|h| h == c).unwrap();
                assert!(v[k].parse::<i64>().is_ok(), "{file}: {c} = {}", v[k]);
            }
            // The other columns stay full-precision floats.
            let k = header.iter().position(|h| *h != cols[0]).unwrap();
            assert!(v[k].parse::<f64>().is_ok(), "{file}: {}", v[k]);
        }
    };
    check(
        "history.csv",
        &[
            "step",
            "stage",
            "iterations",
            "cutbacks",
            "n_contact",
            "n_stick",
            "n_slip",
        ],
    );
    let last = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.contains("contact_") && n.ends_with(".csv"))
        .max()
        .expect("a contact CSV");
    check(&last, &["status"]);
}

//! The condensed stiffness from the partial Cholesky factorisation (retained DOFs ordered
//! last, `S = L_RR L_RRᵀ`) against a dense Schur complement computed independently by
//! Gaussian elimination, with and without grounding springs.

mod common;
use common::*;
use stickslip::assembly::{self, UpperCsc};
use stickslip::condense::Condensed;
use stickslip::dofs::{DofMap, SupportSpec};
use stickslip::elasticity::Material;
use stickslip::la::PartialSymbolic;

/// Dense Schur complement K_RR − K_RI K_II⁻¹ K_IR by Gaussian elimination of the first n_i
/// unknowns of the full symmetric matrix.
fn dense_schur(k: &UpperCsc, n_i: usize) -> Vec<f64> {
    let n = k.n;
    let mut a = vec![0.0; n * n];
    for c in 0..n {
        for p in k.col_ptr[c]..k.col_ptr[c + 1] {
            let r = k.row_idx[p];
            a[r * n + c] = k.values[p];
            a[c * n + r] = k.values[p];
        }
    }
    for p in 0..n_i {
        let piv = a[p * n + p];
        for i in p + 1..n {
            let f = a[i * n + p] / piv;
            if f != 0.0 {
                for j in p..n {
                    a[i * n + j] -= f * a[p * n + j];
                }
            }
        }
    }
    let m = n - n_i;
    (0..m * m)
        .map(|q| a[(n_i + q / m) * n + n_i + q % m])
        .collect()
}

#[test]
fn partial_factorisation_gives_the_schur_complement() {
    let (nodes, tris, sides) = structured(5, 4, 0.0, 2.0, 0.0, 1.0, 0.2);
    let mesh = mesh_from(nodes, tris);
    let [bottom, _, top, _] = &sides;
    let bnodes: Vec<usize> = bottom.iter().flatten().copied().collect();
    let tnodes: Vec<usize> = top.iter().flatten().copied().collect();
    let mat = Material { e: 3.0, nu: 0.25 };
    let elems: Vec<_> = (0..mesh.triangles.len()).map(|e| (e, mat)).collect();
    let active = vec![true; mesh.nodes.len()];
    let sup = [SupportSpec {
        group: "bottom",
        nodes: &bnodes,
        value: [Some(0.0), Some(0.0)],
    }];
    // Retain the pilot (top face) and a few interior nodes in an arbitrary order.
    let retained = [17usize, 3, 40, 29];
    let dofs = DofMap::build(
        &mesh.node_tags,
        &active,
        &sup,
        Some(("top", &tnodes)),
        &retained,
    )
    .unwrap();
    let mut k = UpperCsc::pattern(&mesh, &elems, &dofs);
    assembly::assemble_stiffness(&mesh, &elems, &dofs, &mut k);
    let reference = dense_schur(&k, dofs.n_interior);
    let sym =
        PartialSymbolic::analyse(dofs.n_free(), dofs.n_retained, &k.col_ptr, &k.row_idx).unwrap();
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // Largest entry difference relative to the largest entry of the reference (measured
    // 1.2e-15 and 1.6e-15).
    let tol = 8e-15;
    let mut rel = Vec::new();
    for grounded in [vec![], vec![0, 1]] {
        let c = Condensed::build(&k, dofs.n_interior, &grounded, &sym).unwrap();
        let s = c.s_dense();
        let worst = s
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "grounded {grounded:?}: max |S − S_ref| = {:.2e} of the largest entry",
            worst / scale
        );
        assert!(
            worst < tol * scale,
            "grounded {grounded:?}: |S − S_ref| = {worst:e} (scale {scale:e})"
        );
        rel.push(worst / scale);
    }
    validation_row(
        "090-condense",
        "partial factorisation: `L_RR L_RRᵀ` against a dense Schur complement by Gaussian elimination",
        "second method",
        &format!(
            "{:.1e} relative without grounding, {:.1e} with (asserted < {tol:.0e})",
            rel[0], rel[1]
        ),
        "condense",
    );
}

/// The fields of several contact states from one block solve (as a sweep recovers them for its
/// self-checks, split over the threads, or the output writer, in one sweep) equal those of one
/// solve each, bit for bit: each column sees the same operations in the same order. The
/// per-element displacement table gives each element's displacements as the DOF map does.
#[test]
fn block_recovery_and_kept_element_matrices_equal_the_one_by_one_computation() {
    let (model, sim) = cm_on_l1(&mut |_| Ok(()));
    assert!(sim.failure.is_none(), "{:?}", sim.failure);
    let st = sim.last_state.as_ref().expect("a converged step");
    // Three different right-hand sides: the last state at two load scales, and with its normal
    // forces halved.
    let mut open = st.clone();
    open.f_n.iter_mut().for_each(|f| *f *= 0.5);
    let states = [
        (sim.last_scale, st),
        (0.5 * sim.last_scale, st),
        (sim.last_scale, &open),
    ];
    let block = model.contact_displacements(&states, true);
    assert_eq!(block.len(), 3);
    for (k, (scale, s)) in states.iter().enumerate() {
        let one = model.contact_displacement(*scale, s);
        assert_eq!(one.len(), block[k].len());
        let same = one
            .iter()
            .zip(&block[k])
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(
            same,
            "column {k} of the block solve differs from its own solve"
        );
        assert!(one.iter().any(|v| *v != 0.0), "column {k} is zero");
    }
    assert_ne!(block[0], block[2], "the three right-hand sides must differ");
    // The same block in one sweep on this thread (as the output writer recovers a batch).
    let one_sweep = model.contact_displacements(&states, false);
    for (a, b) in block.iter().zip(&one_sweep) {
        assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
    }
    // Each element's displacements through the model's per-element table are those the DOF
    // map gives node by node (free DOFs, and the supports' prescribed values).
    let u = &block[0];
    for (i, (e, _)) in model.elems.iter().enumerate() {
        let nodes = &model.mesh.triangles[*e].nodes;
        assert_eq!(
            model.element_u(i, u),
            model.dofs.element_displacement(nodes, u),
            "element {e}"
        );
    }
}

/// Any number of fields recovered together (their columns interleaved, up to eight per read of
/// the factor, split over the threads or in one sweep), their equilibrium checks eight at a
/// time and their nodal stresses four at a time give each field's own numbers, bit for bit:
/// what a sweep's rows and the output writer's batches compute equals one field at a time.
#[test]
fn fields_checked_and_stressed_together_equal_one_at_a_time() {
    use stickslip::checks::{Input, equilibrium, equilibrium_many};
    let (model, sim) = cm_on_l1(&mut |_| Ok(()));
    assert!(sim.failure.is_none(), "{:?}", sim.failure);
    let st = sim.last_state.as_ref().expect("a converged step");
    // Nine right-hand sides: the last state at several load scales, with its normal forces
    // scaled, and one with no contact forces at all.
    let varied: Vec<_> = (0..9)
        .map(|k| {
            let mut s = st.clone();
            let f = if k == 4 { 0.0 } else { 1.0 - 0.1 * k as f64 };
            s.f_n.iter_mut().for_each(|v| *v *= f);
            s.f_t.iter_mut().for_each(|v| *v *= f);
            s
        })
        .collect();
    let states: Vec<(f64, &_)> = varied
        .iter()
        .enumerate()
        .map(|(k, s)| (sim.last_scale * (1.0 - 0.05 * k as f64), s))
        .collect();
    let alone: Vec<Vec<f64>> = states
        .iter()
        .map(|(scale, s)| model.contact_displacement(*scale, s))
        .collect();
    for n in 1..=states.len() {
        for spread in [true, false] {
            let block = model.contact_displacements(&states[..n], spread);
            for (k, u) in block.iter().enumerate() {
                assert!(
                    u.iter()
                        .zip(&alone[k])
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "field {k} of {n} recovered together (spread {spread}) differs from its own"
                );
            }
        }
    }
    assert_ne!(alone[0], alone[1], "the right-hand sides must differ");
    let inputs: Vec<Input> = alone
        .iter()
        .zip(&states)
        .map(|(u, (scale, s))| Input {
            model: &model,
            u,
            scale: *scale,
            state: Some(*s),
            records: &sim.records,
            friction: None,
            equilibrium: None,
        })
        .collect();
    let one: Vec<_> = inputs.iter().map(equilibrium).collect();
    assert!(
        one.iter().any(|c| c.value > 0.0),
        "some residual to compare"
    );
    for n in 1..=inputs.len() {
        for (k, c) in equilibrium_many(&inputs[..n]).iter().enumerate() {
            assert_eq!(
                c.value.to_bits(),
                one[k].value.to_bits(),
                "check {k} of {n}"
            );
            assert_eq!(c.note, one[k].note, "check {k} of {n}");
        }
    }
    let fields: Vec<&[f64]> = alone.iter().map(|u| u.as_slice()).collect();
    let stresses: Vec<_> = fields
        .iter()
        .map(|u| model.nodal_stresses(u, false))
        .collect();
    for n in 1..=fields.len() {
        for (k, s) in model.nodal_stresses_many(&fields[..n]).iter().enumerate() {
            let same = s
                .iter()
                .zip(&stresses[k])
                .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
            assert!(same, "stresses of field {k} of {n} differ from its own");
        }
    }
}

/// The shipped Cattaneo–Mindlin case on `vm272_L1`: its model and its simulation (`on_step`
/// sees every step).
fn cm_on_l1(
    on_step: &mut dyn FnMut(
        &stickslip::driver::StepEvent,
    ) -> Result<(), stickslip::error::RunError>,
) -> (stickslip::model::Model, stickslip::driver::Simulation) {
    let case: stickslip::case::Case =
        serde_json::from_value(shipped_case_on("vm272_cm.json", "vm272_L1.msh")).unwrap();
    let model = stickslip::model::Model::build(&case, &repo().join("cases/vm272_cm.json")).unwrap();
    let law = model.friction.clone();
    let sim = stickslip::run::simulate(
        &model,
        &case,
        law.as_ref(),
        stickslip::run::LogLevel::Error,
        on_step,
    )
    .unwrap();
    (model, sim)
}

/// A converged step of the Cattaneo–Mindlin case on L1: (step, time, traction scale, state).
type CmStep = (usize, f64, f64, stickslip::contact::solver::State);

/// The model of the Cattaneo–Mindlin case on L1 and its converged steps.
fn cm_steps_on_l1() -> (stickslip::model::Model, Vec<CmStep>) {
    let mut steps = Vec::new();
    let (model, _) = cm_on_l1(&mut |ev| {
        steps.push((ev.step, ev.time, ev.scale, ev.contact.cloned().unwrap()));
        Ok(())
    });
    (model, steps)
}

/// A step to write from its contact state, with the channel its field is sent back on, if any.
fn step_output(
    s: &CmStep,
    reply: Option<std::sync::mpsc::SyncSender<Vec<f64>>>,
) -> stickslip::output::series::StepOutput {
    stickslip::output::series::StepOutput {
        step: s.0,
        time: s.1,
        scale: s.2,
        u: None,
        contact: Some(s.3.clone()),
        state: None,
        reply,
        physical: None,
    }
}

/// The writer's batches (`Series::write` with several steps: one block solve for their fields,
/// datasets encoded in parallel) write the same files, byte for byte, as one step at a time,
/// and a step's reply channel receives exactly its recovered field.
#[test]
fn a_batch_of_steps_writes_what_one_step_at_a_time_writes() {
    use stickslip::output::series::Series;
    let (model, steps) = cm_steps_on_l1();
    assert!(steps.len() >= 3, "{} steps", steps.len());
    let picked: Vec<_> = [1, steps.len() / 2, steps.len() - 1]
        .iter()
        .map(|&k| steps[k].clone())
        .collect();
    let out = step_output;
    let dir = tempdir("writer-batches");
    let (one, batched) = (dir.join("one"), dir.join("batched"));
    for d in [&one, &batched] {
        std::fs::create_dir_all(d).unwrap();
    }
    let mut series = Series::new(&model, &one, "cm", false);
    for s in &picked {
        series.write(vec![out(s, None)]).unwrap();
    }
    let (tx, rx) = std::sync::mpsc::sync_channel(1);
    let mut series = Series::new(&model, &batched, "cm", false);
    series
        .write(vec![out(&picked[0], None), out(&picked[1], Some(tx))])
        .unwrap();
    series.write(vec![out(&picked[2], None)]).unwrap();
    let replied = rx.recv().expect("the batch sends the field back");
    let own = model.contact_displacement(picked[1].2, &picked[1].3);
    assert!(
        replied.len() == own.len()
            && replied
                .iter()
                .zip(&own)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
        "the reply is not the step's field"
    );
    let mut names: Vec<String> = std::fs::read_dir(&one)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    names.sort();
    assert_eq!(names.len(), 3 * 3 + 1, "{names:?}");
    for name in &names {
        assert!(
            std::fs::read(one.join(name)).unwrap() == std::fs::read(batched.join(name)).unwrap(),
            "{name} differs between one-step and batched writes"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The background writer with the driver's thread helping at the end (`Background::help`:
/// the later half of the waiting steps prepared on the calling thread, put in place by the
/// writer in their turn) writes the same files, byte for byte, as `Series::write` one step at
/// a time; the last step's field reaches the driver whichever thread recovered it. A step the
/// writer cannot put in place stops it there: it is reported, and no file of a later step
/// (prepared by either thread) stays behind, temporary or not.
#[test]
fn the_writer_with_the_driver_helping_writes_what_one_step_at_a_time_writes() {
    use stickslip::output::background::Background;
    use stickslip::output::series::Series;
    let (model, steps) = cm_steps_on_l1();
    assert!(steps.len() >= 6, "{} steps", steps.len());
    let out = step_output;
    let dir = tempdir("writer-helped");
    let (one, helped, failed) = (dir.join("one"), dir.join("helped"), dir.join("failed"));
    for d in [&one, &helped, &failed] {
        std::fs::create_dir_all(d).unwrap();
    }
    let mut series = Series::new(&model, &one, "cm", false);
    for s in &steps {
        series.write(vec![out(s, None)]).unwrap();
    }
    // All the steps queued before the writer can take more than the first: the driver's
    // thread then prepares the later half of those waiting.
    let last = steps.last().unwrap();
    // The steps are handed over in microseconds and the writer's first takes a millisecond
    // or more, so the driver's thread finds steps waiting; tried again (into a clean
    // directory) the rare time it does not.
    let mut replied = None;
    for _ in 0..5 {
        let _ = std::fs::remove_dir_all(&helped);
        std::fs::create_dir_all(&helped).unwrap();
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        let by_driver = std::thread::scope(|scope| {
            let mut writer = Background::spawn(scope, Series::new(&model, &helped, "cm", false));
            for s in &steps[..steps.len() - 1] {
                writer.send(out(s, None)).unwrap();
            }
            writer.send(out(last, Some(tx))).unwrap();
            let by_driver = writer.help();
            let (busy, _) = writer.finish().unwrap();
            assert!(busy > 0.0);
            by_driver
        });
        replied = Some(rx.recv().expect("the last step's field is sent back"));
        if by_driver > 0 {
            break;
        }
        replied = None;
    }
    let replied = replied.expect("the driver's thread prepared no step in five tries");
    let own = model.contact_displacement(last.2, &last.3);
    assert!(
        replied
            .iter()
            .zip(&own)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    assert_same_files(&one, &helped, steps.len(), "helped writes");
    assert_a_failed_step_stops_the_series(
        &model,
        &steps,
        &failed,
        stickslip::output::background::QUEUE,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes `steps` through a writer with a queue of `queue` steps into `failed`, where a step in
/// the middle cannot be put in place (a directory where its bodies file goes): the error names
/// it, no temporary file stays behind, and nothing of the later steps is written.
fn assert_a_failed_step_stops_the_series(
    model: &stickslip::model::Model,
    steps: &[CmStep],
    failed: &std::path::Path,
    queue: usize,
) {
    use stickslip::output::background::Background;
    use stickslip::output::series::Series;
    std::fs::create_dir_all(failed).unwrap();
    let bad = steps[steps.len() / 2].0;
    let bad_name = format!("cm_{bad:04}.vtu");
    std::fs::create_dir_all(failed.join(&bad_name)).unwrap();
    let err = std::thread::scope(|scope| {
        let mut writer =
            Background::spawn(scope, Series::new(model, failed, "cm", false)).with_queue(queue);
        // The error comes once: from the send that finds the writer stopped, else at the end.
        let mut err = None;
        for s in steps {
            if let Err(e) = writer.send(step_output(s, None)) {
                err = Some(e);
                break;
            }
        }
        let _ = writer.help();
        let end = writer.finish();
        err.or(end.err()).expect("the failed step's error")
    });
    assert!(err.to_string().contains(&bad_name), "{err}");
    for name in file_names(failed) {
        assert!(
            !name.starts_with('.'),
            "a temporary file stayed behind: {name}"
        );
        if let Some(k) = name
            .strip_prefix("cm_")
            .and_then(|n| n.strip_suffix(".vtu"))
            .and_then(|n| n.parse::<usize>().ok())
        {
            assert!(k <= bad, "{name} was written after the failed step {bad}");
        }
    }
}

/// The files of `n_steps` steps written one at a time into `one` (a bodies and a contact `.vtu`
/// and a contact table per step, and the `.pvd`) are those in `other`, byte for byte.
fn assert_same_files(one: &std::path::Path, other: &std::path::Path, n_steps: usize, what: &str) {
    let names = file_names(one);
    assert_eq!(names.len(), 3 * n_steps + 1, "{names:?}");
    assert_eq!(file_names(other), names);
    for name in &names {
        assert!(
            std::fs::read(one.join(name)).unwrap() == std::fs::read(other.join(name)).unwrap(),
            "{name} differs between one-step writes and {what}"
        );
    }
}

/// A writer whose queue fills (the driver hands steps over faster than they are written, as
/// in a run that writes every step) has the driver's thread prepare the last steps waiting
/// instead of waiting for the writer: the files are those of one step at a time, byte for byte.
#[test]
fn a_full_queue_has_the_driver_prepare_steps_with_the_same_files() {
    use stickslip::output::background::Background;
    use stickslip::output::series::Series;
    let (model, steps) = cm_steps_on_l1();
    assert!(steps.len() >= 6, "{} steps", steps.len());
    let dir = tempdir("writer-full");
    let (one, full) = (dir.join("one"), dir.join("full"));
    std::fs::create_dir_all(&one).unwrap();
    let mut series = Series::new(&model, &one, "cm", false);
    for s in &steps {
        series.write(vec![step_output(s, None)]).unwrap();
    }
    // With a queue of one step, the second step handed over while the writer prepares the
    // first fills it; tried again (into a clean directory) the rare time the writer keeps up.
    let mut during_sends = 0;
    for _ in 0..5 {
        let _ = std::fs::remove_dir_all(&full);
        std::fs::create_dir_all(&full).unwrap();
        during_sends = std::thread::scope(|scope| {
            let mut writer =
                Background::spawn(scope, Series::new(&model, &full, "cm", false)).with_queue(1);
            for s in &steps {
                writer.send(step_output(s, None)).unwrap();
            }
            let during = writer.prepared_here();
            writer.finish().unwrap();
            during
        });
        if during_sends > 0 {
            break;
        }
    }
    assert!(
        during_sends > 0,
        "the driver's thread prepared no step in five tries"
    );
    assert_same_files(&one, &full, steps.len(), "a full queue");
    // The same with a step that cannot be put in place: the driver's thread prepares steps
    // while the writer fails.
    assert_a_failed_step_stops_the_series(&model, &steps, &dir.join("failed"), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A writer given up without `Background::finish` (the driver returned early with an error, or
/// unwinds) still ends — the thread scope does not wait for it for ever — after writing the
/// steps it was handed.
#[test]
fn a_writer_dropped_without_finish_ends_after_writing_what_it_holds() {
    use stickslip::output::background::Background;
    use stickslip::output::series::Series;
    let (model, steps) = cm_steps_on_l1();
    let dir = tempdir("writer-dropped");
    std::fs::create_dir_all(&dir).unwrap();
    std::thread::scope(|scope| {
        let mut writer = Background::spawn(scope, Series::new(&model, &dir, "cm", false));
        writer.send(step_output(&steps[0], None)).unwrap();
        drop(writer);
    });
    let name = format!("cm_{:04}.vtu", steps[0].0);
    assert!(dir.join(&name).is_file(), "{name} not written");
    let _ = std::fs::remove_dir_all(&dir);
}

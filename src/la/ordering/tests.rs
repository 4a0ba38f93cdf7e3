use super::graph::*;

/// The exact check of the compression refuses a grouping of DOFs that are not
/// indistinguishable, and accepts one that is.
#[test]
fn quotient_checks_the_grouping() {
    // Path 0 - 1 - 2: 0 and 2 have the same open neighbourhood, not the same closed one.
    let (cp, ri) = (vec![0, 1, 3, 5], vec![0, 0, 1, 1, 2]);
    let mut mark = vec![0; 3];
    assert!(quotient(3, &cp, &ri, &[0, 1, 0], 2, &mut mark).is_none());
    assert!(quotient(3, &cp, &ri, &[0, 1, 2], 2, &mut mark).is_some());
    // Triangle 0 - 1 - 2 plus 3 attached to all: 0, 1, 2, 3 all indistinguishable.
    let (cp, ri) = (vec![0, 1, 3, 6, 10], vec![0, 0, 1, 0, 1, 2, 0, 1, 2, 3]);
    let mut mark = vec![0; 4];
    let (g, dof_ptr, dofs) = quotient(4, &cp, &ri, &[0, 0, 0, 0], 6, &mut mark).unwrap();
    assert_eq!(
        (g.n(), g.adj.len(), dof_ptr, dofs),
        (1, 0, vec![0, 4], vec![0, 1, 2, 3])
    );
    // The hash grouping finds it.
    let (g, _, _) = compress(4, &cp, &ri);
    assert_eq!(g.vw, vec![4]);
}

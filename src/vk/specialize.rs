//! Folds a kernel's boolean specialization constants into its control flow before the driver sees
//! it: every `if (X)` on a constant the pipeline fixes becomes a plain branch to the side taken.
//!
//! Why: lavapipe (Mesa 22.3) inlines every function call of a shader *before* it removes the
//! branches its specialization constants made dead, then runs its optimisation loop over the whole
//! inlined body, at a cost that grows faster than the body. The path tracer's megakernel carries
//! every material extension, the environment map, RIS and its reuse behind such branches, so a
//! Cornell box paid for all of them: 25 s of `vkCreateComputePipelines` (docs/history/2026-12-03.md,
//! "the kernels' constants folded before the driver sees them"). Here the untaken side is cut off
//! from the control-flow graph; blocks no branch reaches are never translated, so what they call
//! is never inlined.
//!
//! The module stays valid SPIR-V (the validation layer checks every test's modules) and means
//! exactly what the specialised original means:
//! - Only a conditional branch that heads a selection (`OpSelectionMerge` in its block) is folded:
//!   the merge instruction is dropped and the branch becomes `OpBranch` to the side taken. Loop
//!   exits are left alone.
//! - Conditions known: `OpConstantTrue/False`, the boolean specialization constants with the
//!   pipeline's values (or their defaults), `OpSpecConstantOp` and plain logical operations of
//!   known operands, and an `OpPhi` whose incoming values from the blocks still reached all agree
//!   (glslang's short-circuit `X && y` ends in one). Repeated until nothing more folds.
//! - Blocks no longer reached stay in the module (a construct may still name one as its merge)
//!   but end in `OpUnreachable` without their merge instructions, since what they branched to may
//!   be a construct they no longer sit in; a continue target of a loop still reached keeps its
//!   back edge. A phi keeps the pairs of exactly the blocks that still branch to it, reached or
//!   not: the validator counts the unreached ones among a block's predecessors, and Mesa's
//!   translator skips pairs from blocks it never emitted.

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};

static FOLDING: AtomicBool = AtomicBool::new(true);

/// Turns the folding of every pipeline made afterwards, in this process, on (the default) or off.
/// For measurement only (`umbra-bench pipelines` times both); the renders are the same either way.
pub fn set_folding(enabled: bool) {
    FOLDING.store(enabled, Ordering::Relaxed);
}

/// Whether pipelines made now fold their constants (see [`set_folding`]).
pub fn folding() -> bool {
    FOLDING.load(Ordering::Relaxed)
}

const OP_DECORATE: u32 = 71;
const DECORATION_SPEC_ID: u32 = 1;
const OP_CONSTANT_TRUE: u32 = 41;
const OP_CONSTANT_FALSE: u32 = 42;
const OP_SPEC_CONSTANT_TRUE: u32 = 48;
const OP_SPEC_CONSTANT_FALSE: u32 = 49;
const OP_SPEC_CONSTANT_OP: u32 = 52;
const OP_FUNCTION: u32 = 54;
const OP_FUNCTION_END: u32 = 56;
const OP_LOGICAL_EQUAL: u32 = 164;
const OP_LOGICAL_NOT_EQUAL: u32 = 165;
const OP_LOGICAL_OR: u32 = 166;
const OP_LOGICAL_AND: u32 = 167;
const OP_LOGICAL_NOT: u32 = 168;
const OP_SELECT: u32 = 169;
const OP_PHI: u32 = 245;
const OP_LOOP_MERGE: u32 = 246;
const OP_SELECTION_MERGE: u32 = 247;
const OP_LABEL: u32 = 248;
const OP_BRANCH: u32 = 249;
const OP_BRANCH_CONDITIONAL: u32 = 250;
const OP_SWITCH: u32 = 251;
const OP_UNREACHABLE: u32 = 255;
const OP_TERMINATE_INVOCATION: u32 = 4416;

/// What [`specialize`] did, for the log.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Folded {
    /// Selections whose condition was known and became a plain branch.
    pub branches: usize,
    /// Blocks of the module that no branch reaches any more (and were reached before).
    pub blocks_cut: usize,
}

/// One instruction: where its words start, its opcode and word count.
#[derive(Clone, Copy)]
struct Inst {
    at: usize,
    op: u32,
    len: usize,
}

/// One basic block: its label, its phis, its selection or loop merge (if any) and its terminator.
struct Block {
    label: u32,
    phis: Vec<usize>,
    selection_merge: Option<usize>,
    loop_merge: Option<usize>,
    terminator: usize,
}

/// `words` with the boolean specialization constants of `values` (`(constant_id, value)`, the
/// others at their defaults) folded into its selections, and what was folded. A module it cannot
/// read (truncated, no SPIR-V header) is returned unchanged: the driver reports it.
pub fn specialize(words: &[u32], values: &[(u32, u32)]) -> (Vec<u32>, Folded) {
    let Some(insts) = instructions(words) else {
        return (words.to_vec(), Folded::default());
    };
    let operand = |i: &Inst, k: usize| words[i.at + 1 + k];

    // Spec ids, then every boolean whose value the pipeline fixes.
    let mut spec_ids = HashMap::new();
    for i in insts.iter().filter(|i| i.op == OP_DECORATE && i.len >= 4) {
        if operand(i, 1) == DECORATION_SPEC_ID {
            spec_ids.insert(operand(i, 0), operand(i, 2));
        }
    }
    let given: HashMap<u32, u32> = values.iter().copied().collect();
    let mut known: HashMap<u32, bool> = HashMap::new();
    for i in &insts {
        match i.op {
            OP_CONSTANT_TRUE | OP_CONSTANT_FALSE if i.len == 3 => {
                known.insert(operand(i, 1), i.op == OP_CONSTANT_TRUE);
            }
            OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE if i.len == 3 => {
                let id = operand(i, 1);
                let default = i.op == OP_SPEC_CONSTANT_TRUE;
                let value = spec_ids.get(&id).and_then(|s| given.get(s)).map_or(default, |&v| v != 0);
                known.insert(id, value);
            }
            _ => {}
        }
    }

    let functions = blocks(words, &insts);
    let by_label: Vec<HashMap<u32, usize>> =
        functions.iter().map(|f| f.iter().enumerate().map(|(n, b)| (b.label, n)).collect()).collect();
    let predecessors = |f: usize, taken: &HashMap<usize, u32>| {
        reached_predecessors(words, &insts, &functions[f], &by_label[f], taken)
    };
    let reached_before: usize = (0..functions.len()).map(|f| predecessors(f, &HashMap::new()).len()).sum();

    // The side each folded selection takes, per function by block; grown until nothing more is
    // learnt.
    let mut taken: Vec<HashMap<usize, u32>> = vec![HashMap::new(); functions.len()];
    let mut preds: Vec<HashMap<u32, HashSet<u32>>> =
        (0..functions.len()).map(|f| predecessors(f, &taken[f])).collect();
    loop {
        let mut learnt = evaluate(words, &insts, &mut known);
        for (f, blocks) in functions.iter().enumerate() {
            let mut learnt_here = false;
            for (n, b) in blocks.iter().enumerate() {
                let t = &insts[b.terminator];
                if b.selection_merge.is_none() || t.op != OP_BRANCH_CONDITIONAL || taken[f].contains_key(&n) {
                    continue;
                }
                if let Some(&c) = known.get(&operand(t, 0)) {
                    taken[f].insert(n, if c { operand(t, 1) } else { operand(t, 2) });
                    learnt_here = true;
                }
            }
            if learnt_here {
                preds[f] = predecessors(f, &taken[f]);
                learnt = true;
            }
            for b in blocks {
                let Some(from) = preds[f].get(&b.label) else { continue };
                for &p in &b.phis {
                    let phi = &insts[p];
                    let id = operand(phi, 1);
                    if known.contains_key(&id) {
                        continue;
                    }
                    let incoming: Vec<Option<bool>> = (2..phi.len - 1)
                        .step_by(2)
                        .filter(|&k| from.contains(&operand(phi, k + 1)))
                        .map(|k| known.get(&operand(phi, k)).copied())
                        .collect();
                    if let Some(Some(first)) = incoming.first() {
                        if incoming.iter().all(|v| *v == Some(*first)) {
                            known.insert(id, *first);
                            learnt = true;
                        }
                    }
                }
            }
        }
        if !learnt {
            break;
        }
    }

    // The rewrite:
    // - a folded selection loses its merge and branches to the side taken;
    // - a block no longer reached ends in `OpUnreachable` without its merge (what it branched to
    //   may be a construct it no longer sits in), unless a reached loop names it its continue
    //   target (the loop's back edge);
    // - a phi keeps the pairs of the blocks that still branch to it, reached or not (the validator
    //   counts the unreached ones among a block's predecessors; Mesa skips their pairs).
    let mut out = Vec::with_capacity(words.len());
    out.extend_from_slice(&words[..5]);
    let mut skip: HashSet<usize> = HashSet::new();
    let mut branch_to: HashMap<usize, u32> = HashMap::new();
    let mut unreachable: HashSet<usize> = HashSet::new();
    let mut branching_to: HashMap<u32, HashSet<u32>> = HashMap::new();
    let mut phis: Vec<(usize, u32)> = Vec::new();
    for (f, blocks) in functions.iter().enumerate() {
        for (&n, &label) in &taken[f] {
            skip.extend(blocks[n].selection_merge);
            branch_to.insert(blocks[n].terminator, label);
        }
        let continues: HashSet<u32> = blocks
            .iter()
            .filter(|b| preds[f].contains_key(&b.label))
            .filter_map(|b| b.loop_merge.map(|m| operand(&insts[m], 1)))
            .collect();
        for (n, b) in blocks.iter().enumerate() {
            if n > 0 && !preds[f].contains_key(&b.label) && !continues.contains(&b.label) {
                skip.extend(b.selection_merge.iter().chain(&b.loop_merge));
                unreachable.insert(b.terminator);
            } else {
                for label in successors(words, &insts, blocks, n, &taken[f]) {
                    branching_to.entry(label).or_default().insert(b.label);
                }
            }
            phis.extend(b.phis.iter().map(|&p| (p, b.label)));
        }
    }
    let empty = HashSet::new();
    let phi_from: HashMap<usize, &HashSet<u32>> =
        phis.into_iter().map(|(p, label)| (p, branching_to.get(&label).unwrap_or(&empty))).collect();
    for (k, i) in insts.iter().enumerate() {
        let w = &words[i.at..i.at + i.len];
        if skip.contains(&k) {
            continue;
        } else if unreachable.contains(&k) {
            out.push((1 << 16) | OP_UNREACHABLE);
        } else if let Some(&label) = branch_to.get(&k) {
            out.extend_from_slice(&[(2 << 16) | OP_BRANCH, label]);
        } else if let Some(from) = phi_from.get(&k) {
            let pairs: Vec<u32> =
                w[3..].chunks_exact(2).filter(|pair| from.contains(&pair[1])).flatten().copied().collect();
            out.extend_from_slice(&[(((3 + pairs.len()) as u32) << 16) | OP_PHI, w[1], w[2]]);
            out.extend_from_slice(&pairs);
        } else {
            out.extend_from_slice(w);
        }
    }
    let reached_after: usize = preds.iter().map(HashMap::len).sum();
    let branches = taken.iter().map(HashMap::len).sum();
    (out, Folded { branches, blocks_cut: reached_before - reached_after })
}

/// The module's instructions after the 5-word header; `None` when a word count runs past the end
/// or is zero.
fn instructions(words: &[u32]) -> Option<Vec<Inst>> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        return None;
    }
    let mut insts = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let len = (words[at] >> 16) as usize;
        if len == 0 || at + len > words.len() {
            return None;
        }
        insts.push(Inst { at, op: words[at] & 0xffff, len });
        at += len;
    }
    Some(insts)
}

/// The blocks of each function with a body, in order.
fn blocks(words: &[u32], insts: &[Inst]) -> Vec<Vec<Block>> {
    let mut functions = Vec::new();
    let mut current: Option<Vec<Block>> = None;
    let mut open: Option<Block> = None;
    for (k, i) in insts.iter().enumerate() {
        match i.op {
            OP_FUNCTION => current = Some(Vec::new()),
            OP_FUNCTION_END => {
                if let Some(f) = current.take() {
                    if !f.is_empty() {
                        functions.push(f);
                    }
                }
            }
            OP_LABEL => {
                open = Some(Block {
                    label: words[i.at + 1],
                    phis: Vec::new(),
                    selection_merge: None,
                    loop_merge: None,
                    terminator: k,
                })
            }
            OP_PHI => {
                if let Some(b) = open.as_mut() {
                    b.phis.push(k);
                }
            }
            OP_SELECTION_MERGE => {
                if let Some(b) = open.as_mut() {
                    b.selection_merge = Some(k);
                }
            }
            OP_LOOP_MERGE => {
                if let Some(b) = open.as_mut() {
                    b.loop_merge = Some(k);
                }
            }
            // Every terminator: branches, switch, kill, returns, unreachable, terminate-invocation.
            OP_BRANCH..=OP_UNREACHABLE | OP_TERMINATE_INVOCATION => {
                if let (Some(mut b), Some(f)) = (open.take(), current.as_mut()) {
                    b.terminator = k;
                    f.push(b);
                }
            }
            _ => {}
        }
    }
    functions
}

/// The labels block `n` branches to, with the folded selections of `taken` (block index to the
/// label it branches to).
fn successors(
    words: &[u32],
    insts: &[Inst],
    blocks: &[Block],
    n: usize,
    taken: &HashMap<usize, u32>,
) -> Vec<u32> {
    let t = &insts[blocks[n].terminator];
    let w = &words[t.at + 1..t.at + t.len];
    match (taken.get(&n), t.op) {
        (Some(&label), _) => vec![label],
        (None, OP_BRANCH) => vec![w[0]],
        (None, OP_BRANCH_CONDITIONAL) => vec![w[1], w[2]],
        // selector, default, then (literal, label) pairs; 32-bit selectors only in umbra.
        (None, OP_SWITCH) => std::iter::once(w[1]).chain(w[2..].iter().skip(1).step_by(2).copied()).collect(),
        _ => Vec::new(),
    }
}

/// For each block reached from the first (by label), the reached blocks that branch to it.
fn reached_predecessors(
    words: &[u32],
    insts: &[Inst],
    blocks: &[Block],
    by_label: &HashMap<u32, usize>,
    taken: &HashMap<usize, u32>,
) -> HashMap<u32, HashSet<u32>> {
    let mut preds: HashMap<u32, HashSet<u32>> = HashMap::new();
    preds.insert(blocks[0].label, HashSet::new());
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        for label in successors(words, insts, blocks, n, taken) {
            let Some(&m) = by_label.get(&label) else { continue };
            let first_visit = !preds.contains_key(&label);
            preds.entry(label).or_default().insert(blocks[n].label);
            if first_visit {
                stack.push(m);
            }
        }
    }
    preds
}

/// Adds to `known` the booleans computed from known ones by spec-constant operations and plain
/// logical instructions; whether it learnt any.
fn evaluate(words: &[u32], insts: &[Inst], known: &mut HashMap<u32, bool>) -> bool {
    let mut learnt = false;
    for i in insts {
        let w = &words[i.at + 1..i.at + i.len];
        let (id, op, args) = match i.op {
            OP_SPEC_CONSTANT_OP if w.len() >= 3 => (w[1], w[2], &w[3..]),
            OP_LOGICAL_EQUAL..=OP_SELECT if w.len() >= 3 => (w[1], i.op, &w[2..]),
            _ => continue,
        };
        if known.contains_key(&id) {
            continue;
        }
        let arg = |k: usize| args.get(k).and_then(|a| known.get(a)).copied();
        let value = match op {
            OP_LOGICAL_EQUAL => arg(0).zip(arg(1)).map(|(a, b)| a == b),
            OP_LOGICAL_NOT_EQUAL => arg(0).zip(arg(1)).map(|(a, b)| a != b),
            OP_LOGICAL_OR => match (arg(0), arg(1)) {
                (Some(true), _) | (_, Some(true)) => Some(true),
                (Some(false), Some(false)) => Some(false),
                _ => None,
            },
            OP_LOGICAL_AND => match (arg(0), arg(1)) {
                (Some(false), _) | (_, Some(false)) => Some(false),
                (Some(true), Some(true)) => Some(true),
                _ => None,
            },
            OP_LOGICAL_NOT => arg(0).map(|a| !a),
            OP_SELECT => arg(0).and_then(|c| if c { arg(1) } else { arg(2) }),
            _ => None,
        };
        if let Some(v) = value {
            known.insert(id, v);
            learnt = true;
        }
    }
    learnt
}

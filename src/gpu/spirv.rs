//! A post-pass over a SPIR-V module's words that marks every floating-point arithmetic
//! result `NoContraction`, so that no driver may fuse, reassociate or otherwise rewrite
//! the shader's arithmetic (the CPU mirror does the operations one by one, in order).
//!
//! Why a pass over words: naga, which writes glint's SPIR-V, has no way to ask for the
//! decoration, and the `FPFastMathDefault` execution mode of `SPV_KHR_float_controls2`
//! that would say the same for a whole module is an extension wgpu does not enable. The
//! decoration is core SPIR-V 1.0; Mesa maps it to NIR's `exact` (every inexact algebraic
//! rewrite skipped, `dot` summed in order), and the Vulkan specification forbids a driver
//! to contract a decorated operation.
//!
//! The module is read as SPIR-V's logical layout (specification §2.4): the header, then
//! instructions of `word_count << 16 | opcode`. Decorations go at the end of the
//! annotation section, where §2.4 puts them. The pass knows only what it needs: which
//! ids are float scalar, vector or matrix types, and which opcodes are arithmetic.

/// SPIR-V's magic number, the module's first word.
pub const MAGIC: u32 = 0x0723_0203;
/// `OpExtInstImport`.
const OP_EXT_INST_IMPORT: u32 = 11;
/// `OpExtInst`.
const OP_EXT_INST: u32 = 12;
/// `OpTypeFloat`.
const OP_TYPE_FLOAT: u32 = 22;
/// `OpTypeVector`.
const OP_TYPE_VECTOR: u32 = 23;
/// `OpTypeMatrix`.
const OP_TYPE_MATRIX: u32 = 24;
/// `OpDecorate`.
const OP_DECORATE: u32 = 71;
/// `Decoration::NoContraction`.
pub const NO_CONTRACTION: u32 = 42;

/// The opcodes of SPIR-V's floating-point arithmetic (§3.52.13): `OpFNegate`, `OpFAdd`,
/// `OpFSub`, `OpFMul`, `OpFDiv`, `OpFRem`, `OpFMod`, `OpVectorTimesScalar`,
/// `OpMatrixTimesScalar`, `OpVectorTimesMatrix`, `OpMatrixTimesVector`,
/// `OpMatrixTimesMatrix`, `OpOuterProduct`, `OpDot`. `OpExtInst` of GLSL.std.450 with a
/// float result (normalize, sqrt, pow, ...) is decorated too (see [`forbid_contraction`]).
pub const FLOAT_ARITHMETIC: [u32; 14] = [
    127, 129, 131, 133, 136, 140, 141, 142, 143, 144, 145, 146, 147, 148,
];

/// The annotation opcodes (§2.4, section 9): `OpDecorate`, `OpMemberDecorate`,
/// `OpDecorationGroup`, `OpGroupDecorate`, `OpGroupMemberDecorate`, `OpDecorateId`,
/// `OpDecorateString`, `OpMemberDecorateString`.
const ANNOTATIONS: [u32; 8] = [71, 72, 73, 74, 75, 332, 5632, 5633];

/// The opcodes that may come before the annotations (§2.4, sections 1–8): capabilities,
/// extensions, imports, the memory model, entry points, execution modes, debug strings,
/// names and `OpModuleProcessed`, `OpNop`, `OpSourceContinued`.
const BEFORE_ANNOTATIONS: [u32; 14] = [0, 2, 3, 4, 5, 6, 7, 10, 11, 14, 15, 16, 17, 331];

/// What is wrong with a module handed to the pass.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SpirvError {
    /// Fewer than five words, or the first is not SPIR-V's magic number.
    #[error("not a SPIR-V module (no header or wrong magic number)")]
    NotSpirv,
    /// An instruction's word count is zero or runs past the end.
    #[error("malformed SPIR-V: the instruction at word {at} has word count {count}")]
    BadInstruction {
        /// Its first word's index.
        at: usize,
        /// The word count it claims.
        count: usize,
    },
}

/// One instruction: its opcode and its words (the first word included).
struct Inst<'a> {
    at: usize,
    opcode: u32,
    words: &'a [u32],
}

/// The instructions after the header, in order.
fn instructions(words: &[u32]) -> Result<Vec<Inst<'_>>, SpirvError> {
    if words.len() < 5 || words[0] != MAGIC {
        return Err(SpirvError::NotSpirv);
    }
    let mut out = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        if count == 0 || at + count > words.len() {
            return Err(SpirvError::BadInstruction { at, count });
        }
        out.push(Inst {
            at,
            opcode: words[at] & 0xffff,
            words: &words[at..at + count],
        });
        at += count;
    }
    Ok(out)
}

/// The ids of the float types (scalars, vectors and matrices of floats) and of the
/// GLSL.std.450 import.
fn float_types_and_glsl(insts: &[Inst]) -> (std::collections::HashSet<u32>, Option<u32>) {
    let mut floats = std::collections::HashSet::new();
    let mut glsl = None;
    for i in insts {
        match i.opcode {
            OP_TYPE_FLOAT if i.words.len() >= 2 => {
                floats.insert(i.words[1]);
            }
            OP_TYPE_VECTOR | OP_TYPE_MATRIX
                if i.words.len() >= 3 && floats.contains(&i.words[2]) =>
            {
                floats.insert(i.words[1]);
            }
            OP_EXT_INST_IMPORT if i.words.len() >= 3 => {
                let name: Vec<u8> = i.words[2..].iter().flat_map(|w| w.to_le_bytes()).collect();
                if name.starts_with(b"GLSL.std.450\0") {
                    glsl = Some(i.words[1]);
                }
            }
            _ => {}
        }
    }
    (floats, glsl)
}

/// The result ids of the module's floating-point arithmetic: every [`FLOAT_ARITHMETIC`]
/// instruction, and every GLSL.std.450 `OpExtInst` whose result is a float type.
fn float_results(insts: &[Inst]) -> Vec<u32> {
    let (floats, glsl) = float_types_and_glsl(insts);
    insts
        .iter()
        .filter(|i| i.words.len() >= 3 && floats.contains(&i.words[1]))
        .filter(|i| {
            FLOAT_ARITHMETIC.contains(&i.opcode)
                || (i.opcode == OP_EXT_INST && i.words.len() >= 4 && Some(i.words[3]) == glsl)
        })
        .map(|i| i.words[2])
        .collect()
}

/// The ids already decorated `NoContraction`.
fn decorated(insts: &[Inst]) -> std::collections::HashSet<u32> {
    insts
        .iter()
        .filter(|i| i.opcode == OP_DECORATE && i.words.len() >= 3 && i.words[2] == NO_CONTRACTION)
        .map(|i| i.words[1])
        .collect()
}

/// `words` with an `OpDecorate %id NoContraction` for every floating-point arithmetic
/// result that lacks one, and how many were added. The decorations are inserted after the
/// module's last annotation, or, in a module without any, where the annotations would
/// begin (before the first type, constant, global or function). Nothing else changes.
pub fn forbid_contraction(words: &[u32]) -> Result<(Vec<u32>, usize), SpirvError> {
    let insts = instructions(words)?;
    let have = decorated(&insts);
    let mut add: Vec<u32> = float_results(&insts)
        .into_iter()
        .filter(|id| !have.contains(id))
        .collect();
    add.sort_unstable();
    add.dedup();
    let at = match insts.iter().rposition(|i| ANNOTATIONS.contains(&i.opcode)) {
        Some(k) => insts[k].at + insts[k].words.len(),
        None => insts
            .iter()
            .find(|i| !BEFORE_ANNOTATIONS.contains(&i.opcode))
            .map_or(words.len(), |i| i.at),
    };
    let mut out = Vec::with_capacity(words.len() + 3 * add.len());
    out.extend_from_slice(&words[..at]);
    for &id in &add {
        out.extend_from_slice(&[3 << 16 | OP_DECORATE, id, NO_CONTRACTION]);
    }
    out.extend_from_slice(&words[at..]);
    Ok((out, add.len()))
}

/// The floating-point arithmetic results of `words` that are not decorated
/// `NoContraction`: empty for a module that [`forbid_contraction`] has been over.
pub fn contractible(words: &[u32]) -> Result<Vec<u32>, SpirvError> {
    let insts = instructions(words)?;
    let have = decorated(&insts);
    Ok(float_results(&insts)
        .into_iter()
        .filter(|id| !have.contains(id))
        .collect())
}

/// The GLSL.std.450 instructions that a driver may compute fused whatever the decoration
/// says (Mesa 26.2 keeps their `ffma_weak` and emits `llvm.fmuladd`): `FMix` (46), `Fma`
/// (50) and `Cross` (68); plus the matrix products. glint's shaders write these out as
/// multiplies and adds; this lists any that a module still holds, as `(opcode, ext)`.
pub fn fused_builtins(words: &[u32]) -> Result<Vec<(u32, Option<u32>)>, SpirvError> {
    let insts = instructions(words)?;
    let (_, glsl) = float_types_and_glsl(&insts);
    Ok(insts
        .iter()
        .filter_map(|i| match i.opcode {
            OP_EXT_INST
                if i.words.len() >= 5
                    && Some(i.words[3]) == glsl
                    && [46, 50, 68].contains(&i.words[4]) =>
            {
                Some((i.opcode, Some(i.words[4])))
            }
            143..=147 => Some((i.opcode, None)),
            _ => None,
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-assembled module: header; OpCapability Shader; OpMemoryModel; OpName;
    /// OpDecorate (a binding); %f32 = OpTypeFloat 32; %v3 = OpTypeVector %f32 3;
    /// %u32 = OpTypeInt 32 0; then in a function body %10 = OpFAdd %f32, %11 = OpIAdd
    /// %u32, %12 = OpDot %f32, %13 = OpFMul %v3.
    fn module() -> Vec<u32> {
        let op = |count: u32, opcode: u32| count << 16 | opcode;
        vec![
            MAGIC,
            0x0001_0000,
            0,
            20,
            0, // header
            op(2, 17),
            1, // OpCapability Shader
            op(3, 14),
            0,
            1, // OpMemoryModel Logical GLSL450
            op(3, 5),
            2,
            0, // OpName %2 ""
            op(4, 71),
            3,
            33,
            0, // OpDecorate %3 Binding 0
            op(3, 22),
            4,
            32, // %4 = OpTypeFloat 32
            op(4, 23),
            5,
            4,
            3, // %5 = OpTypeVector %4 3
            op(4, 21),
            6,
            32,
            0, // %6 = OpTypeInt 32 0
            op(5, 54),
            6,
            7,
            0,
            8, // OpFunction (operands not checked)
            op(5, 129),
            4,
            10,
            1,
            1, // %10 = OpFAdd %4
            op(5, 128),
            6,
            11,
            1,
            1, // %11 = OpIAdd %6
            op(5, 148),
            4,
            12,
            1,
            1, // %12 = OpDot %4
            op(5, 133),
            5,
            13,
            1,
            1,         // %13 = OpFMul %5
            op(1, 56), // OpFunctionEnd
        ]
    }

    #[test]
    fn every_float_result_is_decorated_after_the_last_annotation() {
        let before = module();
        assert_eq!(contractible(&before).unwrap(), vec![10, 12, 13]);
        let (after, n) = forbid_contraction(&before).unwrap();
        assert_eq!(n, 3);
        assert!(contractible(&after).unwrap().is_empty());
        // The three decorations sit right after `OpDecorate %3 Binding 0` (words 13..17).
        let at = 17;
        assert_eq!(&after[..at], &before[..at]);
        assert_eq!(
            &after[at..at + 9],
            &[
                3 << 16 | 71,
                10,
                42,
                3 << 16 | 71,
                12,
                42,
                3 << 16 | 71,
                13,
                42
            ]
        );
        assert_eq!(&after[at + 9..], &before[at..]);
        // Idempotent: a second pass adds nothing.
        assert_eq!(forbid_contraction(&after).unwrap(), (after.clone(), 0));
    }

    #[test]
    fn the_integer_add_is_left_alone_and_a_missed_float_op_is_seen() {
        // The twin: decorating only some of the float results leaves `contractible`
        // naming the rest, so a pass that missed an opcode could not pass the test above.
        let mut partial = module();
        partial.splice(17..17, [3 << 16 | 71, 10, 42]);
        assert_eq!(contractible(&partial).unwrap(), vec![12, 13]);
        assert!(!contractible(&partial).unwrap().contains(&11));
    }

    #[test]
    fn without_annotations_the_decorations_go_before_the_types() {
        let mut m = module();
        m.drain(13..17); // the OpDecorate
        let (after, n) = forbid_contraction(&m).unwrap();
        assert_eq!(n, 3);
        assert_eq!(after[13], 3 << 16 | 71);
        assert_eq!(
            after[13 + 9],
            3 << 16 | 22,
            "OpTypeFloat follows the decorations"
        );
    }

    #[test]
    fn malformed_modules_are_errors_not_panics() {
        assert_eq!(forbid_contraction(&[]), Err(SpirvError::NotSpirv));
        assert_eq!(
            forbid_contraction(&[1, 2, 3, 4, 5]),
            Err(SpirvError::NotSpirv)
        );
        let mut m = module();
        m[5] = 0x0000_0011; // word count 0
        assert_eq!(
            forbid_contraction(&m),
            Err(SpirvError::BadInstruction { at: 5, count: 0 })
        );
        let mut m = module();
        let last = m.len() - 1;
        m[last] = 9 << 16 | 56; // runs past the end
        assert!(matches!(
            forbid_contraction(&m),
            Err(SpirvError::BadInstruction { count: 9, .. })
        ));
    }
}

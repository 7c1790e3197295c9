"""Long straight-line Functions cut into pieces that gcc optimises in bounded time.

gcc's optimiser is superlinear in the length of one C function, and CasADi generates one C
function per SX Function: the jump's contact Hessian (about 940,000 instructions) did not compile
at -O1 in 15 minutes, so it ran as -O0 code at about eight times the cost. :func:`split_function`
replays the SX algorithm instruction by instruction and cuts it every ``size`` instructions;
each piece takes the Function's inputs and the work values still needed after its cut (and the
outputs already written), and gives them to the next. :func:`chain` calls the pieces in turn.
Each value is made by the same operation on the same operands as in the whole Function, so the
chained pieces give the same values bit for bit (docs/derivatives.md).
"""
from __future__ import annotations

import casadi as ca

__all__ = ["split_function", "chain", "piece_name"]


def piece_name(name: str, i: int) -> str:
    """The name of piece ``i`` of the Function ``name`` (its symbol in a compiled library)."""
    return f"{name}_p{i}"


def _live_after_cuts(f: ca.Function, cuts: set[int]) -> dict[int, list[int]]:
    """For each cut k: the work slots read at or after instruction k before being written again."""
    live: set[int] = set()
    out: dict[int, list[int]] = {}
    skip = (ca.OP_INPUT, ca.OP_CONST)
    for k in range(f.n_instructions() - 1, -1, -1):
        op, reads = f.instruction_id(k), f.instruction_input(k)
        if op == ca.OP_OUTPUT:
            live.add(reads[0])
        else:
            live.discard(f.instruction_output(k)[0])
            if op not in skip:
                live.update(reads)
        if k in cuts:
            out[k] = sorted(live)
    return out


def split_function(f: ca.Function, size: int) -> list[ca.Function]:
    """SX Function ``f`` as pieces of about ``size`` instructions each (module doc): piece i takes
    f's inputs and piece i-1's carried values (empty for the first) and gives its carried values;
    the last gives f's outputs. A Function of at most 1.25 ``size`` instructions is one piece, itself."""
    n = f.n_instructions()
    cuts = list(range(size, n - size // 4, size))  # no short tail piece
    if not cuts:
        return [f]
    if not f.is_a("SXFunction"):
        raise TypeError(f"split_function: {f.name()} is a {f.class_name()}, not an SX Function")
    live = _live_after_cuts(f, set(cuts))
    ins = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    nonzeros = [[x.nz[j] for j in range(x.nnz())] for x in ins]
    outs = [[ca.SX(0)] * f.nnz_out(i) for i in range(f.n_out())]
    work: list = [None] * f.sz_w()
    pieces: list[ca.Function] = []
    carried: list[int] = []  # work slots carried into the current piece
    written: list[tuple[int, int]] = []  # (output, nonzero) written by earlier pieces, carried too
    start = 0
    for end in cuts + [n]:
        c = ca.SX.sym("c", len(carried) + len(written))
        for i, slot in enumerate(carried):
            work[slot] = c[i]
        for i, (o, j) in enumerate(written):
            outs[o][j] = c[len(carried) + i]
        for k in range(start, end):
            op, reads, (w, *rest) = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
            if op == ca.OP_INPUT:
                work[w] = nonzeros[reads[0]][reads[1]]
            elif op == ca.OP_OUTPUT:
                outs[w][rest[0]] = work[reads[0]]
                written.append((w, rest[0]))
            elif op == ca.OP_CONST:
                work[w] = ca.SX(f.instruction_constant(k))
            elif len(reads) == 1:
                work[w] = ca.SX.unary(op, work[reads[0]])
            else:
                work[w] = ca.SX.binary(op, work[reads[0]], work[reads[1]])
        if end < n:
            carried = live[end]
            res = [ca.vertcat(*[work[s] for s in carried], *[outs[o][j] for o, j in written])]
            names = ["carried_out"]
        else:
            res = [ca.SX(f.sparsity_out(i), ca.vertcat(*o)) for i, o in enumerate(outs)]
            names = f.name_out()
        pieces.append(ca.Function(piece_name(f.name(), len(pieces)), ins + [c], res, f.name_in() + ["carried_in"], names))
        start = end
    return pieces


def chain(name: str, pieces: list[ca.Function]) -> ca.Function:
    """The Function ``name`` that calls :func:`split_function`'s ``pieces`` (SX or compiled) in
    turn: the whole Function's inputs and outputs."""
    if len(pieces) == 1:
        return pieces[0]
    first = pieces[0]
    ins = [ca.MX.sym(first.name_in(i), first.sparsity_in(i)) for i in range(first.n_in() - 1)]
    carried = ca.MX(0, 1)
    for p in pieces[:-1]:
        carried = p.call(ins + [carried])[0]
    last = pieces[-1]
    return ca.Function(name, ins, last.call(ins + [carried]), [first.name_in(i) for i in range(len(ins))],
                       last.name_out())

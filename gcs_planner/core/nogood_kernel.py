"""The probes' nogoods (``bnb._Prober.nogoods``): the partial routes of the relaxation that a
probe proved covered, kept across probes (the found routes only grow, so they stay covered)
and asked by every later probe (``expand_kernel.expand``) as its own kept partial routes are.

Entries live in the arrays of a ``kernel_records.Nogoods`` record, grown when full, linked
back per key (point, critical points visited before it) from a ``key_table_kernel.KeyTable``
beside it.
"""

from __future__ import annotations

import numpy as np

from gcs_planner.core.expand_kernel import Labels
from gcs_planner.core.kernel_records import Nogoods, empty_nogoods
from gcs_planner.core.key_table_kernel import KeyTable, kept_at, key_table, put, with_room
from gcs_planner.runtime.jit import inner, kernel


@kernel
def link(
    head: KeyTable, nxt: np.ndarray, node: np.ndarray, mask: np.ndarray, base: int
) -> KeyTable:
    """Link entries base .. base + len(node) - 1 of the nogood store into ``head`` (or a larger
    copy of it, returned)."""
    head = with_room(head, len(node))
    for x in range(len(node)):
        nxt[base + x] = kept_at(head, node[x], mask[x])
        put(head, node[x], mask[x], base + x)
    return head


@inner
def expanded_rows(labels: Labels, expanded: list) -> tuple:
    """The rows ``expanded`` of ``labels`` as the nogoods take them: (point, key mask, L, k,
    mass, arc, least v, least h, first state, states, and the states v, h, mass)."""
    ne = len(expanded)
    e_node = np.empty(ne, np.int64)
    e_mask = np.empty(ne, np.int64)
    e_L = np.empty(ne)
    e_k = np.empty(ne, np.int64)
    e_mass = np.empty(ne)
    e_arc = np.empty(ne, np.int64)
    e_vmin = np.empty(ne)
    e_hmin = np.empty(ne)
    e_ss = np.empty(ne, np.int64)
    e_sn = np.empty(ne, np.int64)
    total = 0
    for x in range(ne):
        total += labels.sn[expanded[x]]
    e_sv = np.empty(total)
    e_sh = np.empty(total)
    e_sm = np.empty(total)
    sv, sh, sm = labels.pool[0], labels.pool[1], labels.pool[2]
    at = 0
    for x in range(ne):
        lab = expanded[x]
        e_node[x] = labels.node[lab]
        e_mask[x] = labels.key_mask[lab]
        e_L[x] = labels.L[lab]
        e_k[x] = labels.k[lab]
        e_mass[x] = labels.mass[lab]
        e_arc[x] = labels.arc[lab]
        e_vmin[x] = labels.vmin[lab]
        e_hmin[x] = labels.hmin[lab]
        e_ss[x] = at
        e_sn[x] = labels.sn[lab]
        first = labels.ss[lab]
        for c in range(labels.sn[lab]):
            e_sv[at] = sv[first + c]
            e_sh[at] = sh[first + c]
            e_sm[at] = sm[first + c]
            at += 1
    return (e_node, e_mask, e_L, e_k, e_mass, e_arc, e_vmin, e_hmin, e_ss, e_sn, e_sv, e_sh, e_sm)


class NogoodStore:
    """The nogoods of one prober: ``head`` (key -> last entry) and ``store`` (the entries'
    arrays, the first ``entries`` of them and ``states`` of their states in use)."""

    def __init__(self) -> None:
        self.head = key_table()
        self.entries = 0
        self.states = 0
        self.store: Nogoods = empty_nogoods(256, 1024)

    def add(self, node, mask, L, k, mass, arc, vmin, hmin, ss, sn, sv, sh, sm) -> None:  # noqa: ANN001
        """Join the expanded partial routes of a covered probe (``expanded_rows``)."""
        n, s = len(node), len(sv)
        cap_e, cap_s = len(self.store.L), len(self.store.sv)
        if self.entries + n > cap_e or self.states + s > cap_s:
            grown = empty_nogoods(max(2 * cap_e, self.entries + n), max(2 * cap_s, self.states + s))
            for old, new in zip(self.store, grown):
                new[: len(old)] = old
            self.store = grown
        nxt, sL, sk, smass, sarc, svmin, shmin, sss, ssn, ssv, ssh, ssm = self.store
        e0, e1, s0, s1 = self.entries, self.entries + n, self.states, self.states + s
        sL[e0:e1], sk[e0:e1], smass[e0:e1], sarc[e0:e1] = L, k, mass, arc
        svmin[e0:e1], shmin[e0:e1], sss[e0:e1], ssn[e0:e1] = vmin, hmin, ss + s0, sn
        ssv[s0:s1], ssh[s0:s1], ssm[s0:s1] = sv, sh, sm
        self.head = link(self.head, nxt, node, mask, e0)
        self.entries, self.states = e1, s1

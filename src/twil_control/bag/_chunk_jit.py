"""The numba loop listing a decompressed chunk's records (format.chunk_records with jit=True).

Records are ``<u32 header_len><header fields><u32 data_len><data>``; of the header fields only
``op=``, ``conn=`` and ``time=`` are read. Message data records (op 2) go to conn/tm/off/ln,
connection records (op 7) to conn_offs; returns the two counts. Stops at an incomplete record.
"""
from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _u32_at(buf, i):
    return np.int64(buf[i]) | (np.int64(buf[i + 1]) << 8) | (np.int64(buf[i + 2]) << 16) | (np.int64(buf[i + 3]) << 24)


@numba.njit(cache=True)
def scan_chunk(buf, conn, tm, off, ln, conn_offs):
    n = len(buf)
    p = 0
    k = 0
    kc = 0
    while p + 4 <= n:
        hlen = _u32_at(buf, p)
        hend = p + 4 + hlen
        if hend + 4 > n:
            break
        dlen = _u32_at(buf, hend)
        dstart = hend + 4
        if dstart + dlen > n:
            break
        op = -1
        c = -1
        t = np.int64(0)
        i = p + 4
        while i + 4 <= hend:
            flen = _u32_at(buf, i)
            f0 = i + 4
            # field names of interest: op=, conn=, time=
            if flen >= 4 and buf[f0] == 111 and buf[f0 + 1] == 112 and buf[f0 + 2] == 61:  # "op="
                op = buf[f0 + 3]
            elif flen >= 9 and buf[f0] == 99 and buf[f0 + 1] == 111 and buf[f0 + 2] == 110 \
                    and buf[f0 + 3] == 110 and buf[f0 + 4] == 61:  # "conn="
                c = _u32_at(buf, f0 + 5)
            elif flen >= 13 and buf[f0] == 116 and buf[f0 + 1] == 105 and buf[f0 + 2] == 109 \
                    and buf[f0 + 3] == 101 and buf[f0 + 4] == 61:  # "time="
                t = _u32_at(buf, f0 + 5) * 1000000000 + _u32_at(buf, f0 + 9)
            i = f0 + flen
        if op == 2:
            conn[k] = c
            tm[k] = t
            off[k] = dstart
            ln[k] = dlen
            k += 1
        elif op == 7:
            conn_offs[kc] = p
            kc += 1
        p = dstart + dlen
    return k, kc

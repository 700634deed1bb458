"""Scores a render against a reference and its standard error (the oracle's compare.py).

    python score.py CANDIDATE.exr REFERENCE.exr REFERENCE_stderr.exr

Prints compare.py's JSON. A candidate smaller than the reference by a whole factor k in both
axes (a quick run at a fraction of the reference's size) is scored against the reference
averaged over k×k blocks (what a box-filtered render at that size converges to), its standard
error combined accordingly (√Σs² / k²). Run with the oracle's Python (`../shared/oracle/env.sh`)
and ORACLE=path/to/shared/oracle, or from that folder.
"""

import json
import os
import sys

import numpy as np

sys.path.insert(0, os.environ.get("ORACLE", os.path.dirname(os.path.abspath(__file__))))
import compare  # noqa: E402  (the oracle's, found through ORACLE)


def blocks(image, k, combine):
    h, w, c = image.shape
    return combine(image.reshape(h // k, k, w // k, k, c))


def main():
    cand, ref, sref = (compare.read_rgb(p) for p in sys.argv[1:4])
    if cand.shape != ref.shape:
        k = ref.shape[0] // cand.shape[0]
        if k < 1 or cand.shape[0] * k != ref.shape[0] or cand.shape[1] * k != ref.shape[1]:
            print(json.dumps({"error": f"shape {cand.shape} is not the reference's {ref.shape} / k"}))
            sys.exit(1)
        ref = blocks(ref, k, lambda b: b.mean(axis=(1, 3)))
        sref = blocks(sref, k, lambda b: np.sqrt((b**2).sum(axis=(1, 3))) / k**2)
    print(json.dumps(compare.score(cand, ref, sref)))


if __name__ == "__main__":
    main()

"""Runs a Mitsuba 3 script with Dr.Jit's LLVM backend compiling for AVX2, 8 lanes wide.

    python mitsuba_avx2.py SCRIPT [ARGS ...]

Dr.Jit's LLVM backend compiles its kernels for the host's widest vectors: 16 lanes on an AVX-512
machine, 8 on an AVX2 one. This runs SCRIPT (e.g. the oracle's render_ref.py) with the backend
retargeted, after `mi.set_variant`, to a Haswell-class CPU (AVX2 + FMA, 8 lanes) through Dr.Jit's
exported `jit_llvm_set_target(cpu, features, vector_width)`: on an AVX-512 machine it measures
what Mitsuba does on an AVX2 one, on the same cores in the same run (cpu-peers.sh,
MITSUBA_AVX2=1). The images are the same renders; only the kernels' vector width changes.
"""

import ctypes
import os
import runpy
import sys

import drjit
import mitsuba as mi

_core = ctypes.CDLL(os.path.join(os.path.dirname(drjit.__file__), "libdrjit-core.so"))
# void jit_llvm_set_target(const char *target_cpu, const char *target_features, uint32_t width)
_set_target = _core._Z19jit_llvm_set_targetPKcS0_j
_set_target.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32]
_set_variant = mi.set_variant


def set_variant(*args, **kwargs):
    _set_variant(*args, **kwargs)
    # Initialise the LLVM backend (it detects the host), then retarget it.
    drjit.eval(drjit.llvm.Float(1.0))
    _set_target(b"haswell", b"+avx,+avx2,+fma,+f16c,+bmi,+bmi2,+lzcnt,+popcnt,+sse4.2", 8)
    print("mitsuba_avx2: Dr.Jit LLVM target haswell, AVX2, 8 lanes", file=sys.stderr)


mi.set_variant = set_variant
script = os.path.abspath(sys.argv[1])
sys.argv = [script] + sys.argv[2:]
sys.path.insert(0, os.path.dirname(script))
runpy.run_path(script, run_name="__main__")

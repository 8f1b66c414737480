"""Test-suite wide settings.

Small-matrix BLAS calls are many times slower with a threaded OpenBLAS on a
busy 2-core machine, so the suite (and the notebook kernels nbval starts,
which inherit this environment) runs single-threaded BLAS.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

"""The OpenMP waiting the zeroset command line chooses for itself (apps/cli/main.cpp), for the
benchmark programs, which do not go through it: idle workers spin briefly, then sleep
(GOMP_SPINCOUNT=10000), unless the caller chose a policy."""
import os


def cli_openmp_env(**extra):
    """os.environ with the command line's OpenMP waiting, plus `extra`."""
    env = dict(os.environ, **extra)
    if "OMP_WAIT_POLICY" not in env and "GOMP_SPINCOUNT" not in env:
        env["GOMP_SPINCOUNT"] = "10000"
    return env


def describe(env):
    """How the workers wait under `env`, for the reports."""
    if "OMP_WAIT_POLICY" in env:
        return f"`OMP_WAIT_POLICY={env['OMP_WAIT_POLICY']}`"
    return f"idle workers spin `GOMP_SPINCOUNT={env['GOMP_SPINCOUNT']}` times, then sleep"

"""The compiled form of core.trajectory.rotations' rotation kernel (the same bits as its numpy code,
which is used where no C compiler built it: optional); no fused multiply-add, or the bits would
differ. Everything else is in pyproject.toml."""

from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "lorisnb.core.trajectory._rotations",
            sources=["lorisnb/core/trajectory/_rotations.c"],
            extra_compile_args=["-O3", "-ffp-contract=off", "-fno-fast-math"],
            optional=True,
        )
    ]
)

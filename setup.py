"""Build of the optional C extension ``pkmkit.native.kernels`` (everything else about the
package is in pyproject.toml).

The extension holds ahead-of-time twins of the full-pose Numba kernels, so that a fresh
process's first large batch does not pay Numba's import (docs/architecture.md, "Compiled
kernels: Numba and the optional C extension").
It is optional: without a C compiler or the Python headers the build prints a warning and the
package installs without it (the Numba kernels are then used). Plain C, the CPython API and the
buffer protocol only (no NumPy headers); -O3 in ISO C mode without fast-math and with no
floating-point contraction, so that its results are those of the Numba kernels.
"""

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

NATIVE = "src/pkmkit/native/"

#: Flags for GCC and Clang (ISO C: no FMA contraction either way; no -ffast-math).
UNIX_FLAGS = ["-O3", "-std=c11", "-ffp-contract=off", "-fno-fast-math"]


class BuildExt(build_ext):
    """``build_ext`` with the compiler's flags chosen by its type (MSVC takes its own
    defaults: /O2, /fp:precise)."""

    def build_extensions(self) -> None:
        if self.compiler.compiler_type == "unix":
            for ext in self.extensions:
                ext.extra_compile_args = [*UNIX_FLAGS, *ext.extra_compile_args]
        super().build_extensions()


setup(
    ext_modules=[
        Extension(
            "pkmkit.native.kernels",
            sources=[NATIVE + "module.c", NATIVE + "inverse.c", NATIVE + "direct.c",
                     NATIVE + "inverse_simd.c", NATIVE + "position.c", NATIVE + "chain.c",
                     NATIVE + "velocity.c", NATIVE + "pose_velocity.c", NATIVE + "pose_one.c",
                     NATIVE + "svd.c", NATIVE + "rod_velocity.c",
                     NATIVE + "chain_velocity.c", NATIVE + "chain_linearise.c",
                     NATIVE + "chain_one_velocity.c", NATIVE + "chain_one_velocity_doc.c",
                     NATIVE + "chain_one.c", NATIVE + "chain_one_solve.c",
                     NATIVE + "chain_one_pack.c", NATIVE + "chain_one_closure.c",
                     NATIVE + "chain_one_tripteor.c",
                     NATIVE + "chain_one_trimule.c", NATIVE + "chain_closed_rows.c",
                     NATIVE + "rod_one.c",
                     NATIVE + "plain_numbers.c",
                     NATIVE + "rod_batch.c",
                     NATIVE + "angles.c",
                     NATIVE + "recycled.c",
                     NATIVE + "inverse_shared.c", NATIVE + "csv_text.c"],
            depends=[NATIVE + "kernels.h", NATIVE + "chain_face.h", NATIVE + "chain_one.h",
                     NATIVE + "inverse_block.h",
                     NATIVE + "shortest_table.h"],
            optional=True,
        )
    ],
    cmdclass={"build_ext": BuildExt},
)

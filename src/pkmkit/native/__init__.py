"""Ahead-of-time compiled (C) kernels, optional.

``pkmkit.native.kernels`` is a C extension built with the package when a C compiler is
present (``setup.py``; without one the install still succeeds, with a warning, and this
package holds no extension). It holds twins of Numba kernels, with the same
arguments, the same algorithm and statuses, run without the GIL:

- ``inverse_poses`` — :func:`pkmkit.machines.full_pose_kernels.inverse_poses` (eight poses
  per AVX-512 block, four per AVX2 one, on x86-64 CPUs that have them, for machines of slides
  and struts: the same operations lane by lane but sin and cos, which a vectorised sincos
  computes — at most 1 ulp from the exact values on [0, 2π] — or, for rotations up to 1 rad,
  the Taylor series of sin θ / θ and cos θ in θ², so q may differ from the scalar
  and Numba kernels' in its last bits, within 4 ulp of the leg; ``simd()`` gives the poses per
  block in use, 0 for one at a time, ``simd(False)`` switches it off, ``simd(4)`` asks for
  AVX2; ``simd_sincos`` exposes the sincos to the tests);
- ``solve_rows``, ``solve_one`` — :func:`pkmkit.machines.full_pose_direct_kernel.solve_rows`
  and ``solve_one``;
- ``position_rows`` — :func:`pkmkit.machines.full_pose_position_kernel.solve_rows` (the
  position inverse of the Verne-type module);
- ``chain_rows`` — :func:`pkmkit.solve.chain_kernel._solve_rows` (the joint-chain closure and
  machine inverse);
- ``rod_inverse``, ``rod_velocity``, ``rod_field`` (``velocity.c``) — the one-pose inverse
  and velocity model of translational rod machines
  (:meth:`pkmkit.machines.closed_form.RodClosedForm.inverse_one`,
  :class:`pkmkit.machines.velocity_one.OnePoseVelocity`), the batch row's bits;
- ``rod_ik_one``, ``rod_fk_one``, ``rod_jacobian_one`` (``rod_one.c``) — one pose per call of
  a translational rod machine in one call each (``Machine.ik``, ``fk``, ``jacobian`` of a
  plain pose: input checked, solve, stroke test and result array in C; the machine's
  constants packed by :func:`pkmkit.machines.closed_form_one.one_pose_pack`), the Python
  one-pose paths' bits;
- ``pose_velocity`` (``pose_velocity.c``) — the one-pose velocity kernels of six-rod
  full-pose machines (:mod:`pkmkit.machines.full_pose_velocity_kernel`);
- ``pose_one`` (``pose_one.c``; not a twin) — a full-pose machine's constants packed once
  (:func:`pkmkit.machines.full_pose_one.native_one`) into an object whose ``ik``, ``fk`` and
  ``jacobian`` take one plain pose or configuration each in one C call (checks, the kernels
  above, the stroke test; the same bits as ``OnePoseInverse``, ``solve_one`` and
  ``pose_velocity``);
- ``singular_values``, ``singular_rates`` (``svd.c``) —
  :func:`pkmkit.numerics.svd_kernel.singular_values` and
  :func:`pkmkit.numerics.svd_rates_kernel.singular_rates` (batched one-sided Jacobi SVDs of
  small matrices, with the singular values' rates: the workspace studies' conditioning and
  slack gradients);
- ``rod_velocity3``, ``rod_velocity2`` (``rod_velocity.c``) —
  :func:`pkmkit.machines.kernels.velocity3` and ``velocity2`` (the batched velocity summary
  of square translational rod-leg machines), the same bits;
- ``chain_velocity_pack``, ``chain_one_velocity`` (``chain_one_velocity.c``) — no twin: the
  velocity model of one joint-chain configuration at the inverse solution, constants packed
  once per machine (:mod:`pkmkit.machines.chain_one_velocity`);
- ``rod_inverse_rows``, ``rod_reach_det`` (``rod_batch.c``) —
  :func:`pkmkit.machines.kernels.inverse` and ``reach_and_det`` (the batched closed-form
  inverse of rod-leg machines of slides and struts, with the shortfalls and det A that
  ``ik(full_output=True)`` reports), the NumPy reference's bits: a fresh process's
  ``pkmkit ik --input`` takes them without importing Numba;
- ``euler_quat``, ``euler_rotvec`` (``angles.c``; no twin) — the quaternion algebra of a
  table's angles → rotation vectors (:func:`pkmkit.spatial.euler.rotvec_from_angles`) in one
  pass per row, for ``pkmkit ik <full-pose machine> --input``
  (:func:`pkmkit.boundary.coordinates.pose_from_cli`): NumPy keeps the sines, cosines and
  arctan2, so the rows are the NumPy path's bits.
- ``csv_rows`` (``csv_text.c``; no twin) — a table's rows as CSV text, the bytes pyarrow's
  writer gives (shortest round-trip float64s by a Schubfach-style algorithm, integers, coded
  texts), formatted without the GIL, for :class:`pkmkit.io.table.TableWriter`'s CSV output.

Loading it costs a millisecond, where Numba's import and its first compiled call cost
0.8–0.9 s of CPU in a fresh process. Which implementation runs is decided in one place,
:mod:`pkmkit.numerics.jit` (``PKMKIT_NATIVE=0`` disables the extension).
"""

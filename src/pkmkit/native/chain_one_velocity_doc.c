/* The docstrings of native/chain_one_velocity.c's Python face and of chain_one.c's fused
 * chain_one_ik_jacobian (kept apart: those files' 700-line limit). */

const char pk_chain_velocity_pack_doc[] =
    "chain_velocity_pack(frames, types, evar, elements, offsets, position, head, head_position,\n"
    "                    loop_columns, column_leg, n_u, length, tool, slides, signs, turns,\n"
    "                    homes)\n\n"
    "The constants of chain_one_velocity for one joint-chain machine, copied into a capsule:\n"
    "the model arrays of pkmkit.solve.chain_kernel.model_arrays with position (n_var,) the\n"
    "column of each variable in the closure's Jacobian (platform 0-5, the passive joints, then\n"
    "the legs' actuators from n_u on; -1 for none), head (H,) the head's elements,\n"
    "head_position (n_var,) the actuator index of each head actuator (-1 else), loop_columns\n"
    "(n_loop,) the actuator index of each leg actuator, column_leg (n_u,) the leg whose joint\n"
    "alone a column is (-1: the platform's and shared joints'), n_u, the characteristic length,\n"
    "the tool length (m), and the legs' home modes: slides (int64, places in u) with their\n"
    "home signs, revolute joints turns (int64) with their home values homes.";

const char pk_chain_one_velocity_doc[] =
    "chain_one_velocity(pack, u, out[, singular]) -> bound\n\n"
    "The velocity model of one joint-chain configuration u (6 + n_var floats, a list or a\n"
    "float64 array: the platform's position and rotation vector, every joint variable) with\n"
    "the constants of chain_velocity_pack: out (12 n + min(6, n) + 1 + (n_u - 6) n floats) filled\n"
    "with J (6, n), J_homogeneous (6, n), J_homogeneous's singular values, its condition\n"
    "number and the passive joints' rates (n_u - 6, n); returns the lower bound of\n"
    "sigma_min / sigma_max of the closure's Jacobian C_U (0.0 where a pivot vanished, -1.0\n"
    "where u is not in the legs' home modes: out is then not filled). With singular false the\n"
    "singular values and the condition are left NaN: chain_one_velocity(pack, None, out) then\n"
    "computes them from out's J_homogeneous (and returns the condition number); out may there\n"
    "also be the flat view of a writeable copy of a record-layout array (chain_one_ik_jacobian's:\n"
    "the same places for J_homogeneous, the singular values and the condition).";

const char pk_chain_one_jacobian_doc[] =
    "chain_one_jacobian(pack, u, threshold, singular=False) -> out, None or False\n\n"
    "chain_one_velocity's model of one configuration u (6 + n_var floats: a list, or a float64\n"
    "1-D array such as chain_one_ik's solution) in a new float64 array out (its layout, the\n"
    "singular values and the condition NaN: chain_one_velocity(pack, None, out) computes them)\n"
    "where the bound clears threshold; None where it does not (or a pivot vanished), False\n"
    "where u is not in the legs' home modes. singular true: the singular stage runs in the same\n"
    "call (out's singular values and condition filled).";

const char pk_chain_one_ik_jacobian_doc[] =
    "chain_one_ik_jacobian(packed, pack, x, threshold, guard, singular=False, record=False)\n\n"
    "m.jacobian(x)'s C path in one call: chain_one_ik's inverse of one plain pose x (no\n"
    "stroke test) and chain_one_jacobian(pack, u, threshold) at its solution u, the closure's\n"
    "Jacobian handed over from the inverse's last evaluation where that was at u (else\n"
    "evaluated again): (q, out), out the array, None or False as chain_one_jacobian answers\n"
    "(False too where the inverse's largest residual exceeds guard); None where the inverse\n"
    "declines. pack: the machine's chain_velocity_pack capsule. singular true: out's\n"
    "singular values and condition computed in the same call (chain_one_jacobian's).\n"
    "record true: the answer is the array alone in the record layout, a read-only (R, n)\n"
    "float64 array of rows J (6), J_homogeneous (6), the singular values then the condition\n"
    "(1 row, 2 where min(6, n) = n; zero after), the passive rates (n_u - 6), q; None where\n"
    "the bound does not clear; False where the inverse declines or the answer would be False.";

"""The C text of a joint-chain LinuxCNC module (:mod:`pkmkit.export.linuxcnc_chains` fills in
the numbers): pkmkit's chain product, leg closure and tool residual (:mod:`pkmkit.solve.chains`)
and a bounded Gauss–Newton iteration on them, one C function per model.

Placeholders ``@NAME@`` (module name) and ``@TABLES@`` (the machine's numbers) are replaced
textually; the rest is fixed C. Lengths in the module's unit, joint values of revolute joints
in radians inside (degrees at LinuxCNC's interface).
"""

from __future__ import annotations

from pkmkit.export.linuxcnc_rod_c import TURN_C

#: Functions of the chain models: frames, closure rows, tool rows, the solver.
CHAIN_MODEL_C = r"""
/* ---- small 3-D helpers ---- */
static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

""" + TURN_C + r"""
/* ---- the chain product T = D_1 M_1(q_1) D_2 M_2(q_2) ... (pkmkit's chain_pose) ---- */
typedef struct {
    double R[3][3], p[3];          /* the end frame */
    int count;                     /* joints passed */
    int variable[MAX_CHAIN];       /* their variables */
    int type[MAX_CHAIN];           /* JOINT_R or JOINT_P */
    double z[MAX_CHAIN][3];        /* their axes (world) */
    double at[MAX_CHAIN][3];       /* a point of each axis (world) */
} ChainEnd;

/* element e applied to the frame (R, p): p += R d_e, R = R D_e, then the joint's motion */
static void element_step(int e, const double *values, ChainEnd *end)
{
    double R[3][3], c, s, x[3], y[3];
    int i, k, v;
    for (i = 0; i < 3; i++)
        end->p[i] += end->R[i][0] * element_position[e][0] + end->R[i][1] * element_position[e][1]
                     + end->R[i][2] * element_position[e][2];
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++)
            R[i][k] = end->R[i][0] * element_rotation[e][0][k]
                      + end->R[i][1] * element_rotation[e][1][k]
                      + end->R[i][2] * element_rotation[e][2][k];
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++) end->R[i][k] = R[i][k];
    if (element_type[e] == JOINT_F) return;
    v = element_variable[e];
    k = end->count++;
    end->variable[k] = v;
    end->type[k] = element_type[e];
    for (i = 0; i < 3; i++) {
        end->z[k][i] = end->R[i][2];
        end->at[k][i] = end->p[i];
    }
    if (element_type[e] == JOINT_P) {
        for (i = 0; i < 3; i++) end->p[i] += values[v] * end->R[i][2];
        return;
    }
    c = cos(values[v]); s = sin(values[v]);
    for (i = 0; i < 3; i++) { x[i] = end->R[i][0]; y[i] = end->R[i][1]; }
    for (i = 0; i < 3; i++) {
        end->R[i][0] = c * x[i] + s * y[i];
        end->R[i][1] = c * y[i] - s * x[i];
    }
}

/* the end frame of the elements chain[0..count-1] from (R0, p0) */
static void chain_end(const int *chain, int count, const double *values, double R0[3][3],
                      const double p0[3], ChainEnd *end)
{
    int i, k;
    end->count = 0;
    for (i = 0; i < 3; i++) {
        end->p[i] = p0[i];
        for (k = 0; k < 3; k++) end->R[i][k] = R0[i][k];
    }
    for (i = 0; i < count; i++) element_step(chain[i], values, end);
}

/* the motion of a point x of the end body and of its rotation by joint k of a chain:
   dx = z x (x - at) and dw = z (revolute), dx = z and dw = 0 (prismatic) */
static void joint_motion(const ChainEnd *end, int k, const double x[3], double dx[3],
                         double dw[3])
{
    int i;
    if (end->type[k] == JOINT_P) {
        for (i = 0; i < 3; i++) { dx[i] = end->z[k][i]; dw[i] = 0.0; }
        return;
    }
    {
        double arm[3];
        for (i = 0; i < 3; i++) arm[i] = x[i] - end->at[k][i];
        cross3(end->z[k], arm, dx);
        for (i = 0; i < 3; i++) dw[i] = end->z[k][i];
    }
}

/* ---- leg closure (pkmkit's leg_residual): r = (p_leg - p_X, L v / c), M = R_leg R_X^T,
   v = vee(M - M^T) / 2, c = (1 + tr M) / 4 ---- */
static void gibbs(double M[3][3], double v[3], double *c)
{
    v[0] = 0.5 * (M[2][1] - M[1][2]);
    v[1] = 0.5 * (M[0][2] - M[2][0]);
    v[2] = 0.5 * (M[1][0] - M[0][1]);
    *c = 0.25 * (1.0 + M[0][0] + M[1][1] + M[2][2]);
}

/* derivative of L v / c by a world rotation w of the leg's end: L (S(M) / (2c) + v v^T / (2c^2)),
   S(M) = tr(M) I - M (pkmkit's rotation_rows) */
static void rotation_rows(double M[3][3], double G[3][3])
{
    double v[3], c, tr = M[0][0] + M[1][1] + M[2][2];
    int i, k;
    gibbs(M, v, &c);
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++)
            G[i][k] = closure_length * ((i == k ? tr : 0.0) - M[i][k]) * 0.5 / c
                      + closure_length * v[i] * v[k] * 0.5 / (c * c);
}

/* closure rows of leg l: residual r[6] and Jacobian rows J[6][n_u] (zeroed by the caller) with
   respect to (dp_X, dw_X, the unknown variables: column column_of[v], -1 when known) */
static void leg_rows(int l, const double *values, double RX[3][3], const double pX[3],
                     const int *column_of, double r[6], double J[6][MAX_UNKNOWNS])
{
    static const double I3[3][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
    static const double zero[3] = {0.0, 0.0, 0.0};
    ChainEnd end;
    double M[3][3], MT[3][3], G[3][3], GT[3][3], v[3], c;
    int i, k, j;
    chain_end(&leg_element[leg_first[l]], leg_first[l + 1] - leg_first[l], values,
              (double (*)[3])I3, zero, &end);
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++) {
            M[i][k] = end.R[i][0] * RX[k][0] + end.R[i][1] * RX[k][1] + end.R[i][2] * RX[k][2];
            MT[k][i] = M[i][k];
        }
    gibbs(M, v, &c);
    rotation_rows(M, G);
    rotation_rows(MT, GT);
    for (i = 0; i < 3; i++) {
        r[i] = end.p[i] - pX[i];
        r[3 + i] = closure_length * v[i] / c;
        J[i][i] = -1.0;
        for (k = 0; k < 3; k++) J[3 + i][3 + k] = -GT[i][k];
    }
    for (j = 0; j < end.count; j++) {
        double dx[3], dw[3];
        int col = column_of[end.variable[j]];
        if (col < 0) continue;
        joint_motion(&end, j, end.p, dx, dw);
        for (i = 0; i < 3; i++) {
            J[i][col] += dx[i];
            J[3 + i][col] += G[i][0] * dw[0] + G[i][1] * dw[1] + G[i][2] * dw[2];
        }
    }
}

/* the tool frame: the head chain from the platform frame (pkmkit's tool_frame) */
static void tool_end(const double *values, double RX[3][3], const double pX[3], ChainEnd *end)
{
    chain_end(head_element, N_HEAD, values, RX, pX, end);
}

/* the tool point (tool_length along the tool frame's z) and the tool axis (that z) */
static void tool_point_axis(const ChainEnd *end, double point[3], double axis[3])
{
    int i;
    for (i = 0; i < 3; i++) {
        axis[i] = end->R[i][2];
        point[i] = end->p[i] + tool_length * axis[i];
    }
}

/* tool rows of the inverse model (pkmkit's solve_machine_inverse): r = (point - target point,
   L (axis - target axis)) and their Jacobian rows */
static void tool_rows(const double *values, double RX[3][3], const double pX[3],
                      const double target[6], const int *column_of, double r[6],
                      double J[6][MAX_UNKNOWNS])
{
    ChainEnd end;
    double point[3], axis[3], arm[3], t[3];
    int i, j;
    tool_end(values, RX, pX, &end);
    tool_point_axis(&end, point, axis);
    for (i = 0; i < 3; i++) {
        r[i] = point[i] - target[i];
        r[3 + i] = closure_length * (axis[i] - target[3 + i]);
        arm[i] = point[i] - pX[i];
        J[i][i] = 1.0;
    }
    /* a platform rotation w moves the point by w x arm, the axis by w x axis */
    for (j = 0; j < 3; j++) {
        double e[3] = {0.0, 0.0, 0.0};
        e[j] = 1.0;
        cross3(e, arm, t);
        for (i = 0; i < 3; i++) J[i][3 + j] = t[i];
        cross3(e, axis, t);
        for (i = 0; i < 3; i++) J[3 + i][3 + j] = closure_length * t[i];
    }
    for (j = 0; j < end.count; j++) {
        double dx[3], dw[3];
        int col = column_of[end.variable[j]];
        if (col < 0) continue;
        joint_motion(&end, j, point, dx, dw);
        cross3(dw, axis, t);
        for (i = 0; i < 3; i++) {
            J[i][col] += dx[i];
            J[3 + i][col] += closure_length * t[i];
        }
    }
}

/* x mod m in [0, m) */
static double fmod_positive(double x, double m)
{
    return x - m * floor(x / m);
}

/* Gaussian elimination with partial pivoting: solves M x = rhs (size n) in place; 0 when a
   pivot vanishes (singular) */
static int solve_square(int n, double M[MAX_UNKNOWNS][MAX_UNKNOWNS], double *rhs)
{
    int i, k, r, piv;
    for (k = 0; k < n; k++) {
        double best = fabs(M[k][k]);
        piv = k;
        for (r = k + 1; r < n; r++)
            if (fabs(M[r][k]) > best) { best = fabs(M[r][k]); piv = r; }
        if (!(best > 0.0)) return 0;
        if (piv != k) {
            for (i = 0; i < n; i++) { double t = M[k][i]; M[k][i] = M[piv][i]; M[piv][i] = t; }
            { double t = rhs[k]; rhs[k] = rhs[piv]; rhs[piv] = t; }
        }
        for (r = k + 1; r < n; r++) {
            double f = M[r][k] / M[k][k];
            for (i = k; i < n; i++) M[r][i] -= f * M[k][i];
            rhs[r] -= f * rhs[k];
        }
    }
    for (k = n - 1; k >= 0; k--) {
        for (i = k + 1; i < n; i++) rhs[k] -= M[k][i] * rhs[i];
        rhs[k] /= M[k][k];
    }
    return 1;
}

/* ---- a configuration: platform pose and every joint variable ---- */
typedef struct {
    double p[3], R[3][3];
    double values[N_VARIABLES];
} Configuration;

/* the residual rows of a closure (every leg; with target, the tool rows too) and its Jacobian */
static int closure_rows(Configuration *s, const double *target, const int *column_of,
                        double r[MAX_ROWS], double J[MAX_ROWS][MAX_UNKNOWNS], int n_u)
{
    int l, i, k, rows = 6 * N_LEGS + (target ? 6 : 0);
    for (i = 0; i < rows; i++)
        for (k = 0; k < n_u; k++) J[i][k] = 0.0;
    for (l = 0; l < N_LEGS; l++)
        leg_rows(l, s->values, s->R, s->p, column_of, &r[6 * l], &J[6 * l]);
    if (target)
        tool_rows(s->values, s->R, s->p, target, column_of, &r[6 * N_LEGS], &J[6 * N_LEGS]);
    return rows;
}

/* Gauss-Newton on the closure (least squares: the hyperstatic legs give more rows than
   unknowns), each step bounded, at most CHAIN_MAX_ITER steps. Unknowns: the platform (dp, dw)
   then the variables unknown[0..n_unknown-1]. Returns 0 (s solved), PKM_UNREACHABLE (a
   least-squares residual beyond residual_tol: no assembly / the target out of reach),
   PKM_SINGULAR or PKM_NOT_CONVERGED. */
static int solve_closure(Configuration *s, const double *target, const int *unknown,
                         int n_unknown)
{
    double r[MAX_ROWS], J[MAX_ROWS][MAX_UNKNOWNS], N[MAX_UNKNOWNS][MAX_UNKNOWNS];
    double g[MAX_UNKNOWNS];
    int column_of[N_VARIABLES], n_u = 6 + n_unknown, it, i, k, m;
    for (i = 0; i < N_VARIABLES; i++) column_of[i] = -1;
    for (i = 0; i < n_unknown; i++) column_of[unknown[i]] = 6 + i;
    for (it = 0; it <= CHAIN_MAX_ITER; it++) {
        double worst = 0.0, step = 0.0, turn_size = 0.0, size = 1.0, bound = 1.0;
        int rows = closure_rows(s, target, column_of, r, J, n_u);
        for (i = 0; i < rows; i++) {
            if (r[i] != r[i]) return PKM_NOT_CONVERGED;
            if (fabs(r[i]) > worst) worst = fabs(r[i]);
        }
        if (worst <= exact_tol) return 0;
        if (it == CHAIN_MAX_ITER) break;
        for (i = 0; i < n_u; i++) {
            g[i] = 0.0;
            for (m = 0; m < rows; m++) g[i] -= J[m][i] * r[m];
            for (k = 0; k <= i; k++) {
                double sum = 0.0;
                for (m = 0; m < rows; m++) sum += J[m][i] * J[m][k];
                N[i][k] = sum;
                N[k][i] = sum;
            }
        }
        for (i = 0; i < n_u; i++) N[i][i] *= 1.0 + DAMPING;
        if (!solve_square(n_u, N, g)) return PKM_SINGULAR;
        for (i = 0; i < n_u; i++) {
            int v = i < 6 ? -1 : unknown[i - 6];
            double a = fabs(g[i]);
            if (g[i] != g[i]) return PKM_SINGULAR;
            if ((i >= 3 && i < 6) || (v >= 0 && variable_revolute[v])) {
                if (a > turn_size) turn_size = a;
            } else if (a > step) step = a;
            size += i < 3 ? fabs(s->p[i]) : (v >= 0 ? fabs(s->values[v]) : 0.0);
        }
        if (step > max_step) bound = max_step / step;
        if (turn_size * bound > max_turn) bound = max_turn / turn_size;
        for (i = 0; i < 3; i++) { s->p[i] += bound * g[i]; g[3 + i] *= bound; }
        turn(s->R, &g[3]);
        for (i = 6; i < n_u; i++) s->values[unknown[i - 6]] += bound * g[i];
        if (bound == 1.0 && step <= step_tol * size && turn_size <= step_tol) {
            /* stopped at a least-squares solution: exact (pkmkit's residual_tol) or none */
            closure_rows(s, target, column_of, r, J, n_u);
            worst = 0.0;
            for (i = 0; i < rows; i++) if (fabs(r[i]) > worst) worst = fabs(r[i]);
            return worst <= residual_tol ? 0 : PKM_UNREACHABLE;
        }
    }
    return PKM_NOT_CONVERGED;
}

/* 0 when every joint of the machine (actuated and passive) is within its stroke */
static int within_strokes(const double *values)
{
    int v;
    for (v = 0; v < N_VARIABLES; v++)
        if (variable_checked[v] && (values[v] < variable_min[v] || values[v] > variable_max[v]))
            return PKM_OUT_OF_STROKE;
    return 0;
}

/* direct model: the legs' closure for the platform and the passive joints, the actuators
   given, from the configuration s */
static int direct_model(Configuration *s, const double *q)
{
    int j, status;
    for (j = 0; j < N_ACTUATORS; j++) s->values[actuated_variable[j]] = q[j];
    status = solve_closure(s, 0, passive_variable, N_PASSIVE);
    return status != 0 ? status : within_strokes(s->values);
}

/* an angle (rad) wrapped to (-pi, pi] (pkmkit's head_branches.wrapped) */
static double wrapped(double a)
{
    return PI - fmod_positive(PI - a, 2.0 * PI);
}

/* 1 when every joint of s is within its stroke, its revolute actuators taken on the turn
   nearest start (pkmkit's ChainWarmStart._within_strokes) */
static int inside_from(const Configuration *s, const double *start)
{
    Configuration t = *s;
    int j;
    for (j = 0; j < N_ACTUATORS; j++) {
        int v = actuated_variable[j];
        if (variable_revolute[v]) {
            double d = t.values[v] - start[j];
            t.values[v] = start[j] + d - 2.0 * PI * floor((d + PI) / (2.0 * PI));
        }
    }
    return within_strokes(t.values) == 0;
}

/* a two-branch head (turn a, tilt c: (a, c) and (a + pi, -c) give the same tool axis): a
   solution s whose turn is more than pi/2 - flip_margin from the start's turn `reference`, or
   with a joint beyond its stroke, solved again with its head flipped, and the flipped one
   taken when it is exact and it alone
   is within the strokes, or both (or neither) are and its turn is strictly nearer (pkmkit's
   nearest_head_branch) */
static void nearest_head_branch(Configuration *s, const double target[6], double reference,
                                const double *start)
{
    Configuration other;
    int kept, flipped;
    if (head_flip_turn < 0)
        return;
    kept = inside_from(s, start);
    if (kept && !(fabs(wrapped(s->values[head_flip_turn] - reference)) > PI / 2 - flip_margin))
        return; /* near the start and within the strokes: kept */
    other = *s;
    other.values[head_flip_turn] += PI;
    other.values[head_flip_tilt] = -other.values[head_flip_tilt];
    if (solve_closure(&other, target, inverse_variable, N_INVERSE) != 0) return;
    flipped = inside_from(&other, start);
    if ((flipped && !kept)
        || (flipped == kept
            && fabs(wrapped(other.values[head_flip_turn] - reference))
               < fabs(wrapped(s->values[head_flip_turn] - reference))))
        *s = other;
}

/* inverse model: every joint and the platform such that the legs close and the tool reaches
   target (tool point, unit tool axis), from the configuration s; a two-branch head on the
   branch whose turn is nearest the start's; revolute actuators are taken on the turn nearest
   the start */
static int inverse_model(Configuration *s, const double target[6])
{
    double start[N_ACTUATORS], reference = head_flip_turn < 0 ? 0.0 : s->values[head_flip_turn];
    int j, status;
    for (j = 0; j < N_ACTUATORS; j++) start[j] = s->values[actuated_variable[j]];
    status = solve_closure(s, target, inverse_variable, N_INVERSE);
    if (status != 0) return status;
    nearest_head_branch(s, target, reference, start);
    for (j = 0; j < N_ACTUATORS; j++) {
        int v = actuated_variable[j];
        if (variable_revolute[v])
            {
            double d = s->values[v] - start[j];
            s->values[v] = start[j] + d - 2.0 * PI * floor((d + PI) / (2.0 * PI));
        }
    }
    return within_strokes(s->values);
}

/* the home configuration (pkmkit's) */
static void home_configuration(Configuration *s)
{
    int i, k;
    for (i = 0; i < 3; i++) {
        s->p[i] = home_platform_position[i];
        for (k = 0; k < 3; k++) s->R[i][k] = home_platform_rotation[i][k];
    }
    for (i = 0; i < N_VARIABLES; i++) s->values[i] = home_values[i];
}
"""

#: LinuxCNC's interface: world X Y Z A B (the tool point; the tool axis z turned by A about x
#: then B about y), joints in degrees (revolute) or the length unit (prismatic).
CHAIN_INTERFACE_C = r"""
/* the last configuration the module solved (LinuxCNC calls it along the motion): the next
   call starts from it; kinematicsHome resets it */
static Configuration last;
static int last_set = 0, last_is_home = 0;

static int finite_inputs(const double *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!(fabs(v[i]) <= max_coordinate)) return 0;
    return 1;
}

/* tool axis of world angles A, B (degrees): Ry(B) Rx(A) (0, 0, 1) */
static void axis_from_ab(double a, double b, double axis[3])
{
    axis[0] = sin(b * DEG) * cos(a * DEG);
    axis[1] = -sin(a * DEG);
    axis[2] = cos(b * DEG) * cos(a * DEG);
}

/* world angles A, B (degrees) of a unit tool axis */
static void ab_from_axis(const double axis[3], double *a, double *b)
{
    *a = atan2(-axis[1], sqrt(axis[0] * axis[0] + axis[2] * axis[2])) / DEG;
    *b = atan2(axis[0], axis[2]) / DEG;
}

/* solve from the last configuration, then (if that fails and it was not home) from home */
static int solve_from_last(Configuration *s, const double *q, const double *target)
{
    int status = PKM_NOT_CONVERGED;
    if (last_set) {
        *s = last;
        status = q ? direct_model(s, q) : inverse_model(s, target);
    }
    if (status != 0 && !(last_set && last_is_home)) {
        home_configuration(s);
        status = q ? direct_model(s, q) : inverse_model(s, target);
    }
    if (status == 0) { last = *s; last_set = 1; last_is_home = 0; }
    return status;
}

int kinematicsInverse(const EmcPose *pos, double *joints, const KINEMATICS_INVERSE_FLAGS *iflags,
                      KINEMATICS_FORWARD_FLAGS *fflags)
{
    double world[5], target[6];
    Configuration s;
    int j, status;
    (void)iflags;
    (void)fflags;
    world[0] = pos->tran.x; world[1] = pos->tran.y; world[2] = pos->tran.z;
    world[3] = pos->a; world[4] = pos->b;
    if (!finite_inputs(world, 5)) return PKM_INVALID;
    target[0] = world[0]; target[1] = world[1]; target[2] = world[2];
    axis_from_ab(world[3], world[4], &target[3]);
    status = solve_from_last(&s, 0, target);
    if (status != 0) return status;
    for (j = 0; j < N_ACTUATORS; j++) {
        int v = actuated_variable[j];
        joints[j] = variable_revolute[v] ? s.values[v] / DEG : s.values[v];
    }
    return 0;
}

int kinematicsForward(const double *joints, EmcPose *pos, const KINEMATICS_FORWARD_FLAGS *fflags,
                      KINEMATICS_INVERSE_FLAGS *iflags)
{
    double q[N_ACTUATORS], point[3], axis[3];
    Configuration s;
    ChainEnd end;
    int j, status;
    (void)fflags;
    (void)iflags;
    if (!finite_inputs(joints, N_ACTUATORS)) return PKM_INVALID;
    for (j = 0; j < N_ACTUATORS; j++)
        q[j] = variable_revolute[actuated_variable[j]] ? joints[j] * DEG : joints[j];
    status = solve_from_last(&s, q, 0);
    if (status != 0) return status;
    tool_end(s.values, s.R, s.p, &end);
    tool_point_axis(&end, point, axis);
    pos->tran.x = point[0]; pos->tran.y = point[1]; pos->tran.z = point[2];
    ab_from_axis(axis, &pos->a, &pos->b);
    pos->c = 0.0;
    pos->u = 0.0; pos->v = 0.0; pos->w = 0.0;
    return 0;
}

int kinematicsHome(EmcPose *world, double *joint, KINEMATICS_FORWARD_FLAGS *fflags,
                   KINEMATICS_INVERSE_FLAGS *iflags)
{
    double point[3], axis[3];
    ChainEnd end;
    int j;
    home_configuration(&last);
    last_set = 1;
    last_is_home = 1;
    tool_end(last.values, last.R, last.p, &end);
    tool_point_axis(&end, point, axis);
    world->tran.x = point[0]; world->tran.y = point[1]; world->tran.z = point[2];
    ab_from_axis(axis, &world->a, &world->b);
    world->c = 0.0;
    world->u = 0.0; world->v = 0.0; world->w = 0.0;
    for (j = 0; j < N_ACTUATORS; j++) {
        int v = actuated_variable[j];
        joint[j] = variable_revolute[v] ? home_values[v] / DEG : home_values[v];
    }
    *fflags = 0;
    *iflags = 0;
    return 0;
}

KINEMATICS_TYPE kinematicsType(void)
{
    return KINEMATICS_BOTH;
}
"""

#: The realtime module's glue (shared with the rod modules' text).
MODULE_GLUE_C = r"""
int rtapi_app_main(void)
{
    comp_id = hal_init("@NAME@");
    if (comp_id < 0) return comp_id;
    hal_ready(comp_id);
    return 0;
}

void rtapi_app_exit(void)
{
    hal_exit(comp_id);
}

#ifdef KINS_NOT_SWITCHABLE
KINS_NOT_SWITCHABLE
#endif
EXPORT_SYMBOL(kinematicsType);
EXPORT_SYMBOL(kinematicsForward);
EXPORT_SYMBOL(kinematicsInverse);
EXPORT_SYMBOL(kinematicsHome);
MODULE_LICENSE("GPL");
"""

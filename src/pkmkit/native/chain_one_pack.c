/* chain_one_pack: a joint-chain machine's one-pose constants copied into a capsule
 * (native/chain_one.c; machines/chain_one_native.py builds the arguments). */
#include "chain_face.h"
#include "chain_one.h"

/* ---------------------------------------------------------------- packing */

static int check_count(Py_ssize_t nargs, Py_ssize_t expected, const char *name) {
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd positional arguments (%zd given)", name,
                     expected, nargs);
        return -1;
    }
    return 0;
}

static void release_state(PyObject *capsule) {
    pk_one *s = PyCapsule_GetPointer(capsule, PK_ONE_CAPSULE);
    if (!s) return;
    for (int i = 0; i < s->n_owned; i++) free(s->owned[i]);
    free(s);
}

/* A copy of argument obj (type 'd' or 'i', ndim dimensions, `count` entries when >= 0; its
 * count into *got). */
static void *copy_of(pk_one *s, held_buffers *held, PyObject *obj, const char *name, char type,
                     int ndim, Py_ssize_t count, Py_ssize_t *got) {
    void *data = grab(held, obj, name, type, 0, ndim);
    if (!data) return NULL;
    Py_buffer *view = &held->views[held->count - 1];
    Py_ssize_t items = view->len / 8;
    if (count >= 0 && items != count) {
        PyErr_Format(PyExc_ValueError, "%s: %zd entries expected, not %zd", name, count, items);
        return NULL;
    }
    void *copy = malloc((size_t)(items > 0 ? items : 1) * 8);
    if (!copy) {
        PyErr_NoMemory();
        return NULL;
    }
    memcpy(copy, data, (size_t)items * 8);
    s->owned[s->n_owned++] = copy;
    if (got) *got = items;
    return copy;
}

const char pk_chain_one_pack_doc[] =
    "chain_one_pack(frames, types, evar, elements, offsets, head, inv_position, dir_position,\n"
    "               length, inv_options, dir_options, u_home_inv, base, inv_rates, tool,\n"
    "               slides, signs, turns, turn_homes, act_turns, act_turn_homes, lower, upper,\n"
    "               act, wrist, far, u_home_dir, dir_rates, residual_rates, home_values,\n"
    "               singular_bound, max_coordinate, structured, closed=None)\n\n"
    "A joint-chain machine's one-pose constants, copied into a capsule for chain_one_ik and\n"
    "chain_one_fk (machines/chain_one_native.py builds the arguments). wrist: (5,) turn\n"
    "variable, its home, tilt variable, its home, whether the turn reaches a quarter turn, or\n"
    "(0,) for none. structured: block elimination (else the dense solve of chain_rows).\n"
    "closed: the kind's closed-form start, its family (1: TriMule, 2: Tripteor) then its\n"
    "constants (trimule_forms / tripteor_forms native_constants; chain_one.c closed_start).";

PyObject *pk_py_chain_one_pack(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    (void)take_chain;  /* chain_face.h's, unused here */
    if (check_count(nargs, nargs == 34 ? 34 : 33, "chain_one_pack") < 0) return NULL;
    pk_one *s = calloc(1, sizeof(pk_one));
    if (!s) return PyErr_NoMemory();
    held_buffers held = {.count = 0};
    Py_ssize_t n_elem, n_leg_el, n_off, n_head, n_var, got;
    double *frames = copy_of(s, &held, args[0], "frames", 'd', 3, -1, &got);
    if (!frames) goto fail;
    n_elem = got / 16;
    int64_t *types = copy_of(s, &held, args[1], "types", 'i', 1, n_elem, NULL);
    int64_t *evar = types ? copy_of(s, &held, args[2], "evar", 'i', 1, n_elem, NULL) : NULL;
    int64_t *elements = evar ? copy_of(s, &held, args[3], "elements", 'i', 1, -1, &n_leg_el)
                             : NULL;
    int64_t *offsets = elements ? copy_of(s, &held, args[4], "offsets", 'i', 1, -1, &n_off)
                                : NULL;
    int64_t *head = offsets ? copy_of(s, &held, args[5], "head", 'i', 1, -1, &n_head) : NULL;
    int64_t *inv_pos = head ? copy_of(s, &held, args[6], "inv_position", 'i', 1, -1, &n_var)
                            : NULL;
    int64_t *dir_pos = inv_pos ? copy_of(s, &held, args[7], "dir_position", 'i', 1, n_var, NULL)
                               : NULL;
    if (!dir_pos) goto fail;
    let_go(&held);
    if (n_off < 1) {
        PyErr_SetString(PyExc_ValueError, "offsets: one entry at least");
        goto fail;
    }
    if (in_range(types, n_elem, 0, 3, "types") < 0
        || in_range(elements, n_leg_el, 0, n_elem, "elements") < 0
        || in_range(head, n_head, 0, n_elem, "head") < 0
        || in_range(offsets, n_off, 0, n_leg_el + 1, "offsets") < 0
        || in_range(inv_pos, n_var, 6, 6 + n_var, "inv_position") < 0
        || in_range(dir_pos, n_var, -1, 6 + n_var, "dir_position") < 0)
        goto fail;
    for (Py_ssize_t e = 0; e < n_elem; e++)
        if (types[e] != 0 && (evar[e] < 0 || evar[e] >= n_var)) {
            PyErr_Format(PyExc_ValueError, "evar[%zd] out of range", e);
            goto fail;
        }
    for (Py_ssize_t leg = 0; leg + 1 < n_off; leg++)
        if (offsets[leg + 1] < offsets[leg]) {
            PyErr_SetString(PyExc_ValueError, "offsets must not decrease");
            goto fail;
        }
    ptrdiff_t n_dir = 6;
    for (Py_ssize_t v = 0; v < n_var; v++)
        if (dir_pos[v] >= 0) n_dir++;
    for (Py_ssize_t v = 0; v < n_var; v++)
        if (dir_pos[v] >= n_dir) {
            PyErr_SetString(PyExc_ValueError, "dir_position: columns beyond the unknowns");
            goto fail;
        }
    double length = PyFloat_AsDouble(args[8]);
    if (length == -1.0 && PyErr_Occurred()) goto fail;
    pk_chain base_chain = {frames, types, evar, elements, offsets, inv_pos, head,
                           n_off - 1, n_var, 6 + n_var, n_head, length, 1};
    s->inv = base_chain;
    s->dir = base_chain;
    s->dir.position = dir_pos;
    s->dir.n = n_dir;
    s->dir.inverse = 0;
    s->m_dir = 6 * (n_off - 1);
    s->twists = n_leg_el + n_head + 1;
    double *opts[2];
    for (int i = 0; i < 2; i++) {
        opts[i] = copy_of(s, &held, args[9 + i], "options", 'd', 1, 7, NULL);
        if (!opts[i]) goto fail;
        let_go(&held);
        pk_chain_options *o = i == 0 ? &s->inv_o : &s->dir_o;
        o->max_iter = (int64_t)opts[i][0];
        o->xtol = opts[i][1], o->atol = opts[i][2], o->gtol = opts[i][3];
        o->stall = opts[i][4], o->residual_tol = opts[i][5], o->damping = opts[i][6];
    }
    Py_ssize_t n_s, n_t, n_at, n_act, n_w;
    s->u_home_inv = copy_of(s, &held, args[11], "u_home_inv", 'd', 1, 6 + n_var, NULL);
    s->base = s->u_home_inv ? copy_of(s, &held, args[12], "base", 'd', 1, 6, NULL) : NULL;
    s->inv_rates = s->base ? copy_of(s, &held, args[13], "inv_rates", 'd', 2, 6 * (6 + n_var),
                                     NULL) : NULL;
    if (!s->inv_rates) goto fail;
    let_go(&held);
    s->tool = PyFloat_AsDouble(args[14]);
    if (s->tool == -1.0 && PyErr_Occurred()) goto fail;
    s->slides = copy_of(s, &held, args[15], "slides", 'i', 1, -1, &n_s);
    s->signs = s->slides ? copy_of(s, &held, args[16], "signs", 'd', 1, n_s, NULL) : NULL;
    s->turns = s->signs ? copy_of(s, &held, args[17], "turns", 'i', 1, -1, &n_t) : NULL;
    s->turn_homes = s->turns ? copy_of(s, &held, args[18], "turn_homes", 'd', 1, n_t, NULL) : NULL;
    s->act_turns = s->turn_homes ? copy_of(s, &held, args[19], "act_turns", 'i', 1, -1, &n_at)
                                 : NULL;
    s->act_turn_homes = s->act_turns ? copy_of(s, &held, args[20], "act_turn_homes", 'd', 1,
                                               n_at, NULL) : NULL;
    s->lower = s->act_turn_homes ? copy_of(s, &held, args[21], "lower", 'd', 1, n_var, NULL)
                                 : NULL;
    s->upper = s->lower ? copy_of(s, &held, args[22], "upper", 'd', 1, n_var, NULL) : NULL;
    s->act = s->upper ? copy_of(s, &held, args[23], "act", 'i', 1, -1, &n_act) : NULL;
    double *wrist = s->act ? copy_of(s, &held, args[24], "wrist", 'd', 1, -1, &n_w) : NULL;
    if (!wrist) goto fail;
    let_go(&held);
    s->n_slides = n_s, s->n_turns = n_t, s->n_act_turns = n_at, s->n_act = n_act;
    if (in_range(s->slides, n_s, 6, 6 + n_var, "slides") < 0
        || in_range(s->turns, n_t, 6, 6 + n_var, "turns") < 0
        || in_range(s->act_turns, n_at, 0, n_var, "act_turns") < 0
        || in_range(s->act, n_act, 0, n_var, "act") < 0)
        goto fail;
    if (n_act < 1 || n_act > 64 || (n_w != 0 && n_w != 5)) {
        PyErr_SetString(PyExc_ValueError, "1 to 64 actuators; wrist (5,) or (0,)");
        goto fail;
    }
    s->wrist = n_w == 5;
    if (s->wrist) {
        s->w_turn = (int64_t)wrist[0], s->w_home = wrist[1], s->w_tilt = (int64_t)wrist[2];
        s->w_centre = wrist[3], s->wide = wrist[4] != 0.0;
        if (s->w_turn < 0 || s->w_turn >= n_var || s->w_tilt < 0 || s->w_tilt >= n_var) {
            PyErr_SetString(PyExc_ValueError, "wrist: variables out of range");
            goto fail;
        }
    }
    s->far = PyFloat_AsDouble(args[25]);
    if (s->far == -1.0 && PyErr_Occurred()) goto fail;
    s->u_home_dir = copy_of(s, &held, args[26], "u_home_dir", 'd', 1, n_dir, NULL);
    s->dir_rates = s->u_home_dir ? copy_of(s, &held, args[27], "dir_rates", 'd', 2,
                                           n_dir * n_act, NULL) : NULL;
    s->residual_rates = s->dir_rates ? copy_of(s, &held, args[28], "residual_rates", 'd', 2,
                                               s->m_dir * n_act, NULL) : NULL;
    s->home_values = s->residual_rates ? copy_of(s, &held, args[29], "home_values", 'd', 1,
                                                 n_var, NULL) : NULL;
    if (!s->home_values) goto fail;
    let_go(&held);
    s->singular_bound = PyFloat_AsDouble(args[30]);
    if (s->singular_bound == -1.0 && PyErr_Occurred()) goto fail;
    s->max_coordinate = PyFloat_AsDouble(args[31]);
    if (s->max_coordinate == -1.0 && PyErr_Occurred()) goto fail;
    s->structured = PyObject_IsTrue(args[32]);
    if (s->structured < 0) goto fail;
    if (nargs == 34 && args[33] != Py_None) {  /* the closed-form start: family, constants */
        Py_ssize_t n_cl;
        double *cl = copy_of(s, &held, args[33], "closed", 'd', 1, -1, &n_cl);
        if (!cl) goto fail;
        int family = n_cl > 0 ? (int)cl[0] : 0;
        Py_ssize_t want = family == PK_CLOSED_TRIMULE ? 8 : family == PK_CLOSED_TRIPTEOR ? 26 : -1;
        if (n_cl == want && n_cl - 1 <= (Py_ssize_t)(sizeof s->cl / sizeof s->cl[0])
            && n_var == (family == PK_CLOSED_TRIMULE ? 21 : 15)) {
            memcpy(s->cl, cl + 1, (size_t)(n_cl - 1) * sizeof(double));
            s->closed = family;
        }
        let_go(&held);
    }
    int found_inv = pk_one_find_blocks(s, &s->inv, &s->inv_b);
    int found_dir = found_inv == -2 ? -2 : pk_one_find_blocks(s, &s->dir, &s->dir_b);
    if (found_inv == -2 || found_dir == -2) {
        PyErr_NoMemory();
        goto fail;
    }
    PyObject *capsule = PyCapsule_New(s, PK_ONE_CAPSULE, release_state);
    if (!capsule) goto fail;
    return capsule;
fail:
    let_go(&held);
    for (int i = 0; i < s->n_owned; i++) free(s->owned[i]);
    free(s);
    return NULL;
}


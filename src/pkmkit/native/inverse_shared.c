/* The full-pose inverse model of one batch on several threads with no tail: every thread
 * calls pk_inverse_shared with the same plan (issue 22 §2, docs/benchmarks.md "Session 35").
 *
 * Why: with pieces drawn from a shared counter (pkmkit.numerics.jit.run_chunks), a thread
 * descheduled by a competing process in the middle of its piece holds the call until the
 * scheduler runs it again (1.7-15 ms median, session 34), however small the pieces: the
 * held piece has one owner. Taking over the unstarted rest of a held piece is not enough
 * either: the rows its owner is computing at that moment stay held. So here a held row can be
 * computed again by another thread, and written once:
 *
 * - The rows go in slices of slice_rows rows, the slices in blocks of block_slices; each
 *   slice has a flag: 0 free, 1 claimed (its rows being written), 2 written.
 * - A thread takes blocks from a shared counter and, in each, its slices from the first:
 *   it computes a slice into its own scratch (no shared memory written), then claims it by
 *   compare-and-swap 0 -> 1, copies the scratch into q and status, and stores 2 (release).
 *   A slice it finds claimed, or fails to claim, ends its block: a thief took the rest.
 * - A thread that finds no block left steals: from the last slice of every block down, the
 *   free slices, each the same way (compute into scratch, claim, copy), until it meets a
 *   claimed one. A descheduled owner's slice is thus computed by the thief and claimed by
 *   whichever finishes first; the loser discards its scratch.
 * - The calling thread (wait = 1) then waits until every slice is 2 (acquire): a claimed
 *   slice is only ever a copy of slice_rows rows in progress (nanoseconds, unless its writer
 *   was descheduled between the claim and the store: the one window left). The helpers
 *   (wait = 0) return at once, and the call returns without waiting for them: the result
 *   is complete, and a late helper writes nothing any more (every claim fails).
 *
 * Each row is written exactly once, by the thread that claimed its slice (a compare-and-swap
 * decides), after which nobody writes it; the caller reads q only after seeing every flag at
 * 2 with acquire, which orders the copies before. A row may be computed twice (at most one
 * slice per thread and block where an owner and a thief meet), never written twice; its bits
 * are those of the row alone (the vectorised kernel gives every row the same arithmetic,
 * partial blocks included). A late helper still reads x (the call's buffers keep it alive)
 * for a slice it will fail to claim.
 *
 * The plan: a zeroed writable byte buffer of pk_inverse_plan_bytes(rows, ...) bytes; from its
 * first 64-byte aligned address: int64 slice_rows, block_slices, rows; at +64 the block
 * counter (its own cache line); at +128 each block's flags, one cache line (or several) per
 * block so that two threads claiming in their own blocks do not share a line. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <sched.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "kernels.h"

#define PK_LINE 64

static ptrdiff_t least(ptrdiff_t a, ptrdiff_t b) { return a < b ? a : b; }

static unsigned char *plan_base(unsigned char *plan) {
    uintptr_t at = (uintptr_t)plan;
    return plan + ((PK_LINE - at % PK_LINE) % PK_LINE);
}

static ptrdiff_t stride_of(ptrdiff_t block_slices) {
    return (block_slices + PK_LINE - 1) / PK_LINE * PK_LINE;
}

ptrdiff_t pk_inverse_plan_bytes(ptrdiff_t rows, ptrdiff_t slice_rows, ptrdiff_t block_slices) {
    ptrdiff_t slices = (rows + slice_rows - 1) / slice_rows;
    ptrdiff_t blocks = (slices + block_slices - 1) / block_slices;
    return PK_LINE + 2 * PK_LINE + blocks * stride_of(block_slices);
}

void pk_inverse_plan_init(unsigned char *plan, ptrdiff_t rows, ptrdiff_t slice_rows,
                          ptrdiff_t block_slices) {
    int64_t head[3] = {slice_rows, block_slices, rows};
    memcpy(plan_base(plan), head, sizeof head);
}

int pk_inverse_plan_fits(unsigned char *plan, ptrdiff_t bytes, ptrdiff_t rows) {
    if (bytes < 3 * PK_LINE) return 0;
    int64_t head[3];
    memcpy(head, plan_base(plan), sizeof head);
    if (head[0] < 1 || head[1] < 1 || head[2] != rows) return 0;
    return bytes >= pk_inverse_plan_bytes(rows, head[0], head[1]);
}

ptrdiff_t pk_inverse_plan_slice(unsigned char *plan) {
    int64_t slice_rows;
    memcpy(&slice_rows, plan_base(plan), sizeof slice_rows);
    return slice_rows;
}

typedef struct {
    const double *x;
    ptrdiff_t rows, slice_rows, block_slices, slices, blocks, stride;
    const pk_rods *rods;
    const pk_actuators *act;
    double *q;          /* (rows, n) */
    int64_t *status;    /* (rows,) or NULL */
    int64_t *next;      /* the block counter */
    unsigned char *flags;
    double *scratch_q;  /* (slice_rows, n) */
    int64_t *scratch_status;
    double *rod_q;
} job;

static unsigned char *flag_of(const job *j, ptrdiff_t s) {
    ptrdiff_t b = s / j->block_slices;
    return j->flags + b * j->stride + s % j->block_slices;
}

/* Slice s computed into the scratch, then claimed and copied; 0 when another thread had
 * claimed it (the scratch is discarded). */
static int do_slice(job *j, ptrdiff_t s) {
    ptrdiff_t start = s * j->slice_rows;
    ptrdiff_t count = least(j->slice_rows, j->rows - start);
    ptrdiff_t n = j->act->n;
    /* the slice's lines of q asked for (to write) while it is computed: the copy below then
     * stores into cache rather than waiting on each line (a hint, no access) */
    const char *lines = (const char *)(j->q + n * start);
    for (size_t at = 0; at < sizeof(double) * (size_t)(n * count); at += PK_LINE)
        __builtin_prefetch(lines + at, 1, 3);
    if (j->status)
        for (size_t at = 0; at < sizeof(int64_t) * (size_t)count; at += PK_LINE)
            __builtin_prefetch((const char *)(j->status + start) + at, 1, 3);
    pk_inverse_poses(j->x + 6 * start, count, j->rods, j->act, j->scratch_q,
                     j->scratch_status, j->rod_q);
    unsigned char expected = 0;
    if (!__atomic_compare_exchange_n(flag_of(j, s), &expected, 1, 0, __ATOMIC_ACQUIRE,
                                     __ATOMIC_RELAXED))
        return 0;
    memcpy(j->q + n * start, j->scratch_q, sizeof(double) * (size_t)(n * count));
    if (j->status)
        memcpy(j->status + start, j->scratch_status, sizeof(int64_t) * (size_t)count);
    __atomic_store_n(flag_of(j, s), 2, __ATOMIC_RELEASE);
    return 1;
}

static ptrdiff_t block_end(const job *j, ptrdiff_t b) {
    return least((b + 1) * j->block_slices, j->slices);
}

static void own_blocks(job *j) {
    for (;;) {
        ptrdiff_t b = (ptrdiff_t)__atomic_fetch_add(j->next, 1, __ATOMIC_RELAXED);
        if (b >= j->blocks) return;
        for (ptrdiff_t s = b * j->block_slices; s < block_end(j, b); s++)
            if (__atomic_load_n(flag_of(j, s), __ATOMIC_RELAXED) != 0 || !do_slice(j, s))
                break;
    }
}

static void steal(job *j) {
    for (ptrdiff_t b = j->blocks - 1; b >= 0; b--) {
        ptrdiff_t first = b * j->block_slices, s = block_end(j, b) - 1;
        while (s >= first && __atomic_load_n(flag_of(j, s), __ATOMIC_RELAXED) != 0)
            s--; /* the slices thieves took already */
        for (; s >= first; s--)
            if (__atomic_load_n(flag_of(j, s), __ATOMIC_RELAXED) != 0 || !do_slice(j, s))
                break;
    }
}

static void wait_written(const job *j) {
    for (ptrdiff_t s = 0; s < j->slices; s++) {
        for (unsigned spins = 0; __atomic_load_n(flag_of(j, s), __ATOMIC_ACQUIRE) != 2;
             spins++) {
            if (spins >= 64) sched_yield(); /* its writer is descheduled mid-copy */
        }
    }
}

void pk_inverse_shared(const double *x, ptrdiff_t rows, const pk_rods *rods,
                      const pk_actuators *act, double *q, int64_t *status,
                      unsigned char *plan, int wait, double *scratch_q,
                      int64_t *scratch_status, double *rod_q) {
    unsigned char *base = plan_base(plan);
    int64_t head[3];
    memcpy(head, base, sizeof head); /* checked by pk_inverse_plan_fits */
    job j = {.x = x, .rows = rows, .slice_rows = head[0], .block_slices = head[1],
             .rods = rods, .act = act, .q = q, .status = status,
             .next = (int64_t *)(base + PK_LINE), .flags = base + 2 * PK_LINE,
             .scratch_q = scratch_q, .scratch_status = scratch_status, .rod_q = rod_q};
    j.slices = (rows + j.slice_rows - 1) / j.slice_rows;
    j.blocks = (j.slices + j.block_slices - 1) / j.block_slices;
    j.stride = stride_of(j.block_slices);
    own_blocks(&j);
    steal(&j);
    if (wait) wait_written(&j);
}

const char pk_inverse_shared_doc[] =
    "inverse_poses_shared(x, kind, ..., consistency_tol, q, status, plan, wait)\n\n"
    "inverse_poses over one batch by every thread that calls it with the same plan\n"
    "(inverse_plan(rows, slice_rows, block_slices)): blocks from a shared counter, then the\n"
    "free slices of the others' blocks from their ends; each slice computed into the thread's\n"
    "scratch and written once, by the thread that claims it (inverse_shared.c). wait true (the\n"
    "calling thread): returns once every row is written; false (helpers): once there is\n"
    "nothing left to take. An empty status (0,) writes no status. Runs without the GIL.";

const char pk_inverse_plan_doc[] =
    "inverse_plan(rows, slice_rows, block_slices)\n\n"
    "A zeroed plan (bytearray) for inverse_poses_shared over rows rows: slices of slice_rows\n"
    "rows, blocks of block_slices slices (inverse_shared.c).";

PyObject *pk_py_inverse_plan(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3) {
        PyErr_SetString(PyExc_TypeError, "inverse_plan() takes 3 positional arguments");
        return NULL;
    }
    Py_ssize_t v[3];
    for (int i = 0; i < 3; i++) {
        v[i] = PyNumber_AsSsize_t(args[i], PyExc_OverflowError);
        if (v[i] == -1 && PyErr_Occurred()) return NULL;
    }
    if (v[0] < 0 || v[1] < 1 || v[2] < 1 || v[1] > ((Py_ssize_t)1 << 40)
        || v[2] > ((Py_ssize_t)1 << 20)) {
        PyErr_SetString(PyExc_ValueError,
                        "inverse_plan: rows >= 0, slice_rows >= 1, block_slices >= 1 needed");
        return NULL;
    }
    PyObject *plan = PyByteArray_FromStringAndSize(NULL, pk_inverse_plan_bytes(v[0], v[1], v[2]));
    if (!plan) return NULL;
    memset(PyByteArray_AS_STRING(plan), 0, (size_t)PyByteArray_GET_SIZE(plan));
    pk_inverse_plan_init((unsigned char *)PyByteArray_AS_STRING(plan), v[0], v[1], v[2]);
    return plan;
}

unsigned char *pk_take_plan(PyObject *obj, Py_buffer *view, Py_ssize_t rows) {
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) {
        PyErr_SetString(PyExc_TypeError, "plan: a writable bytearray is needed");
        return NULL;
    }
    if (!pk_inverse_plan_fits(view->buf, view->len, rows)) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_ValueError, "plan: not made by inverse_plan for these rows");
        return NULL;
    }
    return view->buf;
}

int pk_run_shared(const double *x, ptrdiff_t rows, const pk_rods *rods,
                  const pk_actuators *act, double *q, int64_t *status, unsigned char *plan,
                  int wait, double *rod_q) {
    size_t k = (size_t)pk_inverse_plan_slice(plan);
    double *scratch_q = malloc(sizeof(double) * (size_t)(act->n > 0 ? act->n : 1) * k);
    int64_t *scratch_status = malloc(sizeof(int64_t) * k);
    int failed = !scratch_q || !scratch_status;
    if (!failed) {
        Py_BEGIN_ALLOW_THREADS
        pk_inverse_shared(x, rows, rods, act, q, status, plan, wait, scratch_q,
                          scratch_status, rod_q);
        Py_END_ALLOW_THREADS
    }
    free(scratch_q);
    free(scratch_status);
    if (failed) PyErr_NoMemory();
    return failed ? -1 : 0;
}

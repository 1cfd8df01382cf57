/* Recycled output blocks: the memory of a large batch call's output (the hexapod's q of
 * 10^6 poses, 48 MB) handed back to the next call once the caller has dropped every array
 * on it, instead of fresh pages that Linux maps and clears on every call (issue 22 §2,
 * docs/benchmarks.md "Session 34").
 *
 * recycled_block(nbytes) returns a writable buffer object over nbytes of memory; NumPy's
 * frombuffer views hold it (through their base) as long as any view lives, so its
 * deallocation is the exact moment no array uses the memory any more — no reference
 * counting guesses. The block's memory then goes to a short list of idle blocks
 * (IDLE_BLOCKS, the oldest freed beyond it) from which a later request of the same size
 * takes it; blocks in use are on no list, so one idle block serves a loop of
 * q = m.ik(X), where the old q is dropped after the new call returns. Everything here runs with the GIL held (the factory and tp_dealloc), so the
 * list needs no other lock. recycled_release() frees the idle blocks and returns their
 * bytes. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>
#ifdef __linux__
#include <sys/mman.h>
#endif

#include "kernels.h"

#define IDLE_BLOCKS 1 /* a loop of q = m.ik(X) alternates two blocks: one idle */
#define BLOCK_ALIGN ((size_t)1 << 21) /* 2 MiB: a transparent huge page */

typedef struct {
    PyObject_HEAD
    void *data;
    Py_ssize_t size;
} Block;

static void *idle_data[IDLE_BLOCKS];
static Py_ssize_t idle_size[IDLE_BLOCKS];
static int idle_count;

static void *block_memory(Py_ssize_t size) {
    size_t rounded = ((size_t)size + BLOCK_ALIGN - 1) / BLOCK_ALIGN * BLOCK_ALIGN;
    void *data = NULL;
    if (posix_memalign(&data, BLOCK_ALIGN, rounded) != 0)
        return NULL;
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(data, rounded, MADV_HUGEPAGE); /* as NumPy does for large arrays; advice only */
#endif
    return data;
}

static void block_dealloc(Block *self) {
    if (self->data != NULL) {
        if (idle_count == IDLE_BLOCKS) { /* the oldest idle block is freed */
            free(idle_data[0]);
            memmove(idle_data, idle_data + 1, (IDLE_BLOCKS - 1) * sizeof(void *));
            memmove(idle_size, idle_size + 1, (IDLE_BLOCKS - 1) * sizeof(Py_ssize_t));
            idle_count--;
        }
        idle_data[idle_count] = self->data;
        idle_size[idle_count] = self->size;
        idle_count++;
    }
    Py_TYPE(self)->tp_free((PyObject *)self);
}

static int block_getbuffer(Block *self, Py_buffer *view, int flags) {
    return PyBuffer_FillInfo(view, (PyObject *)self, self->data, self->size, 0, flags);
}

static PyBufferProcs block_buffer = {(getbufferproc)block_getbuffer, NULL};

static PyTypeObject BlockType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "pkmkit.native.kernels.RecycledBlock",
    .tp_basicsize = sizeof(Block),
    .tp_dealloc = (destructor)block_dealloc,
    .tp_as_buffer = &block_buffer,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Writable memory of a batch output; recycled when no view uses it.",
};

const char pk_recycled_block_doc[] =
    "recycled_block(nbytes) -> a writable buffer of nbytes bytes (2 MiB aligned, huge pages "
    "advised), the memory of an idle block of the same size when one exists (its old "
    "contents: like numpy.empty, nothing is initialised), else new memory. When the block "
    "is deallocated (no view of it left) its memory becomes idle for the next request.";

PyObject *pk_py_recycled_block(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 1) {
        PyErr_SetString(PyExc_TypeError, "recycled_block takes one argument (nbytes)");
        return NULL;
    }
    Py_ssize_t size = PyLong_AsSsize_t(args[0]);
    if (size == -1 && PyErr_Occurred())
        return NULL;
    if (size <= 0) {
        PyErr_SetString(PyExc_ValueError, "recycled_block: nbytes must be positive");
        return NULL;
    }
    if (!(BlockType.tp_flags & Py_TPFLAGS_READY) && PyType_Ready(&BlockType) < 0)
        return NULL;
    void *data = NULL;
    for (int i = idle_count - 1; i >= 0; i--) /* the most recently freed first */
        if (idle_size[i] == size) {
            data = idle_data[i];
            memmove(idle_data + i, idle_data + i + 1, (idle_count - 1 - i) * sizeof(void *));
            memmove(idle_size + i, idle_size + i + 1,
                    (idle_count - 1 - i) * sizeof(Py_ssize_t));
            idle_count--;
            break;
        }
    if (data == NULL && (data = block_memory(size)) == NULL)
        return PyErr_NoMemory();
    Block *block = PyObject_New(Block, &BlockType);
    if (block == NULL) {
        free(data);
        return NULL;
    }
    block->data = data;
    block->size = size;
    return (PyObject *)block;
}

const char pk_recycled_release_doc[] =
    "recycled_release() -> the bytes of the idle blocks, freed now.";

PyObject *pk_py_recycled_release(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    (void)args;
    if (nargs != 0) {
        PyErr_SetString(PyExc_TypeError, "recycled_release takes no arguments");
        return NULL;
    }
    Py_ssize_t total = 0;
    for (int i = 0; i < idle_count; i++) {
        total += idle_size[i];
        free(idle_data[i]);
    }
    idle_count = 0;
    return PyLong_FromSsize_t(total);
}

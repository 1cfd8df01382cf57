/* csv_text.c: a table's rows as CSV text, the bytes pyarrow's CSV writer gives (issue 22 §5).
 *
 * Numbers: a float64 is written in its shortest round-trip digits (the fewest significant
 * digits that read back to the same double; among those, the closest to it; a tie to the even
 * digit), found by a Schubfach-style algorithm (R. Giulietti, "The Schubfach way to render
 * doubles", 2021): the rounding interval of the double, scaled by 10^-k with a 126-bit
 * approximation g of 10^-k (shortest_table.h, computed exactly by tools/shortest_table.py)
 * and rounded to odd, decides which of the multiples of 10^(k+1), then of 10^k, lie in it.
 * Layout as pyarrow's (double-conversion's ToShortest with exponent range -7 < e < 10):
 * positional when the leading digit's decimal exponent e10 is -6 <= e10 <= 9 ("100",
 * "0.000001", "123.5"), else "1.5e+16", "2.5e-7", "5e-324"; "-0", "nan", "inf", "-inf".
 * Integers in decimal; a text column as given codes into given byte strings (quoted already
 * by the caller when the table needs it).
 *
 * csv_rows(columns, start, stop) -> bytes: rows start..stop-1 of the columns (a tuple; each a
 * 1-D buffer of float64 or of an integer type, any stride, or a pair (codes, labels): a 1-D
 * integer buffer and a tuple of bytes), cells joined by ',' and rows ended by '\n', formatted
 * without the GIL (several threads may format disjoint row ranges at once).
 *
 * Raises TypeError for a column of another type or shape, ValueError for a row range beyond
 * a column or a code outside its labels. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

#include "shortest_table.h"

typedef unsigned __int128 pk_u128;

#define Q_MIN (-1074)
#define C_MIN (1ull << 52)
#define MASK63 ((1ull << 63) - 1)

/* floor(q log10 2), floor(log10(3/4 2^q)), floor(e log2 10): exact over the exponents met
 * (checked by tools/shortest_table.py) */
static inline int flog10pow2(int q) { return (int)(((int64_t)q * 661971961083LL) >> 41); }
static inline int flog10tq(int q) {
    return (int)(((int64_t)q * 661971961083LL - 274743187321LL) >> 41);
}
static inline int flog2pow10(int e) { return (int)(((int64_t)e * 913124641741LL) >> 38); }

/* cp g 2^-127 rounded to odd (the low bit set when inexact), g = g1 2^63 + g0 */
static inline uint64_t rop(uint64_t g1, uint64_t g0, uint64_t cp) {
    uint64_t x1 = (uint64_t)(((pk_u128)g0 * cp) >> 64);
    pk_u128 y = (pk_u128)g1 * cp;
    uint64_t y0 = (uint64_t)y, y1 = (uint64_t)(y >> 64);
    uint64_t z = (y0 >> 1) + x1;
    uint64_t vbp = y1 + (z >> 63);
    return vbp | (((z & MASK63) + MASK63) >> 63);
}

/* the shortest decimal f 10^e of c 2^q (c > 0) */
static void shortest(int q, uint64_t c, uint64_t *f, int *e) {
    uint64_t out = c & 1, cb = c << 2, cbr = cb + 2, cbl;
    int k;
    if (c != C_MIN || q == Q_MIN) { /* regular spacing of the doubles about c 2^q */
        cbl = cb - 2;
        k = flog10pow2(q);
    } else { /* c 2^q is a power of two: the interval below is half as wide */
        cbl = cb - 1;
        k = flog10tq(q);
    }
    int h = q + flog2pow10(-k) + 2;
    const uint64_t *g = pk_g[k - PK_K_MIN];
    uint64_t vb = rop(g[0], g[1], cb << h);
    uint64_t vbl = rop(g[0], g[1], cbl << h);
    uint64_t vbr = rop(g[0], g[1], cbr << h);
    uint64_t s = vb >> 2;
    if (s >= 10) { /* one digit fewer: a multiple of 10^(k+1) in the interval (at most one) */
        uint64_t sp10 = 10 * (s / 10), tp10 = sp10 + 10;
        int upin = vbl + out <= sp10 << 2, wpin = (tp10 << 2) + out <= vbr;
        if (upin != wpin) {
            *f = upin ? sp10 : tp10;
            *e = k;
            return;
        }
    }
    uint64_t t = s + 1;
    int uin = vbl + out <= s << 2, win = (t << 2) + out <= vbr;
    *e = k;
    if (uin != win) {
        *f = uin ? s : t;
        return;
    }
    uint64_t twice = (s + t) << 1; /* both in: the closer to c 2^q, a tie to the even */
    *f = (vb < twice || (vb == twice && (s & 1) == 0)) ? s : t;
}

static const char DIGITS2[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* the decimal digits of u (u < 10^20) into p (right-aligned in 20 bytes); their count */
static int digits_of(uint64_t u, char *end) {
    char *p = end;
    while (u >= 100) {
        unsigned r = (unsigned)(u % 100);
        u /= 100;
        p -= 2;
        memcpy(p, DIGITS2 + 2 * r, 2);
    }
    if (u >= 10) {
        p -= 2;
        memcpy(p, DIGITS2 + 2 * u, 2);
    } else {
        *--p = (char)('0' + u);
    }
    return (int)(end - p);
}

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "csv_text.c stores digits as little-endian words"
#endif

static const uint64_t P10[20] = {
    1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull, 1000000ull, 10000000ull, 100000000ull,
    1000000000ull, 10000000000ull, 100000000000ull, 1000000000000ull, 10000000000000ull,
    100000000000000ull, 1000000000000000ull, 10000000000000000ull, 100000000000000000ull,
    1000000000000000000ull, 10000000000000000000ull};

/* the count of decimal digits of u >= 1 */
static inline int count_digits(uint64_t u) {
    int t = ((64 - __builtin_clzll(u)) * 1233) >> 12; /* floor(log10 2^bits), off by <= 1 */
    return t + (u >= P10[t]);
}

/* the eight decimal digits of v < 10^8 (leading zeros included) as ASCII bytes, the first
 * in the lowest byte: halves, quarters, digits split in the lanes of one word */
static inline uint64_t eight_digits(uint32_t v) {
    uint64_t x = v;
    uint64_t hi = (x * 109951163) >> 40; /* x / 10^4, exact for x < 10^8 */
    uint64_t y = hi | ((x - hi * 10000) << 32);
    uint64_t q = ((y * 10486) >> 20) & 0x0000007F0000007Full; /* each 32-bit lane / 100 */
    y = q | ((y - q * 100) << 16);
    q = ((y * 103) >> 10) & 0x000F000F000F000Full; /* each 16-bit lane / 10 */
    y = q | ((y - q * 10) << 8);
    return y + 0x3030303030303030ull;
}

/* x as pyarrow writes a float64 into p; the bytes written (at most 25:
 * "-0.0000012345678901234567"). It may write up to DOUBLE_ROOM bytes from p (whole words):
 * the caller's room. */
#define DOUBLE_ROOM 32
static int write_double(double x, char *p) {
    uint64_t bits;
    memcpy(&bits, &x, 8);
    char *start = p;
    int bq = (int)((bits >> 52) & 0x7ff);
    uint64_t t = bits & (C_MIN - 1);
    if (bq == 0x7ff) {
        if (t) { memcpy(p, "nan", 3); return 3; }
        if (bits >> 63) { memcpy(p, "-inf", 4); return 4; }
        memcpy(p, "inf", 3);
        return 3;
    }
    if (bits >> 63) *p++ = '-';
    if (bq == 0 && t == 0) { *p++ = '0'; return (int)(p - start); }
    uint64_t f;
    int e;
    if (bq != 0) {
        int mq = 1075 - bq; /* the double is (C_MIN | t) 2^-mq */
        uint64_t c = C_MIN | t;
        if (0 < mq && mq < 53 && ((c >> mq) << mq) == c) { /* an integer below 2^53 */
            f = c >> mq;
            e = 0;
        } else {
            shortest(-mq, c, &f, &e);
        }
    } else {
        shortest(Q_MIN, t, &f, &e);
    }
    while (f % 100000000 == 0) { f /= 100000000; e += 8; } /* at most 16 zeros */
    if (f % 10000 == 0) { f /= 10000; e += 4; }
    if (f % 100 == 0) { f /= 100; e += 2; }
    if (f % 10 == 0) { f /= 10; e += 1; }
    int n = count_digits(f); /* f < 10^17 */
    int e10 = e + n - 1;     /* the decimal exponent of the leading digit */
    uint64_t full = f * P10[17 - n]; /* the digits and zeros after them: 17 digits */
    uint64_t lead = full / 10000000000000000ull, rest = full - lead * 10000000000000000ull;
    char d0 = (char)('0' + lead);
    uint64_t a = eight_digits((uint32_t)(rest / 100000000));
    uint64_t b = eight_digits((uint32_t)(rest % 100000000));
    if (e10 < -6 || e10 > 9) { /* d.ddde+XX */
        p[0] = d0;
        p[1] = '.';
        memcpy(p + 2, &a, 8);
        memcpy(p + 10, &b, 8);
        p += n > 1 ? n + 1 : 1;
        *p++ = 'e';
        *p++ = e10 < 0 ? '-' : '+';
        unsigned m = (unsigned)(e10 < 0 ? -e10 : e10);
        if (m >= 100) {
            *p++ = (char)('0' + m / 100);
            memcpy(p, DIGITS2 + 2 * (m % 100), 2);
            p += 2;
        } else if (m >= 10) {
            memcpy(p, DIGITS2 + 2 * m, 2);
            p += 2;
        } else {
            *p++ = (char)('0' + m);
        }
        return (int)(p - start);
    }
    if (e10 < 0) { /* 0.000ddd */
        memcpy(p, "0.000000", 8);
        p += 1 - e10;
        p[0] = d0;
        memcpy(p + 1, &a, 8);
        memcpy(p + 9, &b, 8);
        return (int)(p + n - start);
    }
    /* ddd000 or ddd.ddd: the first k = e10 + 1 digits, a point if more follow */
    int k = e10 + 1;
    pk_u128 w = (pk_u128)a | ((pk_u128)b << 64), low = (((pk_u128)1) << (8 * (k - 1))) - 1;
    pk_u128 with_point = (w & low) | ((pk_u128)'.' << (8 * (k - 1))) | ((w & ~low) << 8);
    p[0] = d0;
    memcpy(p + 1, &with_point, 16);
    p[17] = (char)(w >> 120);
    return (int)(p + (n > k ? n + 1 : k) - start);
}

static int write_integer(int64_t v, int is_unsigned, char *p) {
    char buf[20];
    uint64_t u;
    int neg = 0;
    if (is_unsigned || v >= 0) {
        u = (uint64_t)v;
    } else {
        neg = 1;
        u = 0 - (uint64_t)v;
    }
    int n = digits_of(u, buf + 20);
    if (neg) *p++ = '-';
    memcpy(p, buf + 20 - n, (size_t)n);
    return n + neg;
}

enum { COL_DOUBLE, COL_INT, COL_LABELS };

typedef struct {
    int kind;
    char code;      /* the integer's struct code (b B h H i I l L q Q) */
    Py_buffer view; /* the values or the codes */
    int have_view;
    PyObject *labels; /* COL_LABELS: a tuple of bytes */
    Py_ssize_t width; /* the widest cell */
} Column;

static int integer_code(const char *format, char *code) {
    if (!format) return 0;
    if (*format == '@' || *format == '=' || *format == '<') format++;
    if (strlen(format) != 1 || !strchr("bBhHiIlLqQ", format[0])) return 0;
    *code = format[0];
    return 1;
}

static int64_t read_integer(const Column *col, Py_ssize_t i, int *is_unsigned) {
    const char *at = (const char *)col->view.buf + i * col->view.strides[0];
    *is_unsigned = 0;
    switch (col->code) {
    case 'b': { int8_t v; memcpy(&v, at, 1); return v; }
    case 'B': { uint8_t v; memcpy(&v, at, 1); return v; }
    case 'h': { int16_t v; memcpy(&v, at, 2); return v; }
    case 'H': { uint16_t v; memcpy(&v, at, 2); return v; }
    case 'i': { int32_t v; memcpy(&v, at, 4); return v; }
    case 'I': { uint32_t v; memcpy(&v, at, 4); return v; }
    case 'l': { long v; memcpy(&v, at, sizeof v); return (int64_t)v; }
    case 'L': { unsigned long v; memcpy(&v, at, sizeof v); *is_unsigned = 1; return (int64_t)v; }
    case 'q': { long long v; memcpy(&v, at, 8); return (int64_t)v; }
    default: { unsigned long long v; memcpy(&v, at, 8); *is_unsigned = 1; return (int64_t)v; }
    }
}

static int open_view(PyObject *obj, Py_buffer *view, Py_ssize_t stop) {
    if (PyObject_GetBuffer(obj, view, PyBUF_RECORDS_RO) < 0) return -1;
    if (view->ndim != 1) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_TypeError, "csv_rows: a column must be one-dimensional");
        return -1;
    }
    if (view->shape[0] < stop) {
        PyBuffer_Release(view);
        PyErr_SetString(PyExc_ValueError, "csv_rows: the rows go beyond a column");
        return -1;
    }
    return 0;
}

static int open_column(PyObject *obj, Py_ssize_t stop, Column *col) {
    col->have_view = 0;
    col->labels = NULL;
    if (PyTuple_Check(obj)) {
        if (PyTuple_GET_SIZE(obj) != 2 || !PyTuple_Check(PyTuple_GET_ITEM(obj, 1))) {
            PyErr_SetString(PyExc_TypeError, "csv_rows: a text column is (codes, labels)");
            return -1;
        }
        col->kind = COL_LABELS;
        col->labels = PyTuple_GET_ITEM(obj, 1);
        col->width = 0;
        for (Py_ssize_t j = 0; j < PyTuple_GET_SIZE(col->labels); j++) {
            PyObject *label = PyTuple_GET_ITEM(col->labels, j);
            if (!PyBytes_Check(label)) {
                PyErr_SetString(PyExc_TypeError, "csv_rows: labels must be bytes");
                return -1;
            }
            if (PyBytes_GET_SIZE(label) > col->width) col->width = PyBytes_GET_SIZE(label);
        }
        obj = PyTuple_GET_ITEM(obj, 0);
    } else {
        col->kind = COL_INT;
        col->width = 20;
    }
    if (open_view(obj, &col->view, stop) < 0) return -1;
    col->have_view = 1;
    const char *format = col->view.format;
    if (col->kind == COL_INT && format &&
        (!strcmp(format, "d") || !strcmp(format, "<d") || !strcmp(format, "=d"))) {
        col->kind = COL_DOUBLE;
        col->width = DOUBLE_ROOM;
        return 0;
    }
    if (!integer_code(format, &col->code)) {
        PyErr_Format(PyExc_TypeError, "csv_rows: a column of format %s (float64 or integers)",
                     format ? format : "B");
        return -1;
    }
    return 0;
}

/* rows start..stop-1 into p; the end, or NULL for a code outside its labels */
static char *format_rows(const Column *cols, Py_ssize_t ncols, Py_ssize_t start,
                         Py_ssize_t stop, char *p) {
    for (Py_ssize_t i = start; i < stop; i++) {
        for (Py_ssize_t j = 0; j < ncols; j++) {
            const Column *col = cols + j;
            if (j) *p++ = ',';
            if (col->kind == COL_DOUBLE) {
                double x;
                memcpy(&x, (const char *)col->view.buf + i * col->view.strides[0], 8);
                p += write_double(x, p);
                continue;
            }
            int is_unsigned;
            int64_t v = read_integer(col, i, &is_unsigned);
            if (col->kind == COL_INT) {
                p += write_integer(v, is_unsigned, p);
                continue;
            }
            Py_ssize_t size = PyTuple_GET_SIZE(col->labels);
            if (is_unsigned ? (uint64_t)v >= (uint64_t)size : (v < 0 || v >= size)) return NULL;
            PyObject *label = PyTuple_GET_ITEM(col->labels, v);
            memcpy(p, PyBytes_AS_STRING(label), (size_t)PyBytes_GET_SIZE(label));
            p += PyBytes_GET_SIZE(label);
        }
        *p++ = '\n';
    }
    return p;
}

const char pk_csv_rows_doc[] =
"csv_rows(columns, start, stop) -> bytes: rows start..stop-1 of the columns as CSV text,\n"
"pyarrow's bytes (shortest round-trip float64s); each column a 1-D float64 or integer\n"
"buffer, or (codes, labels: tuple of bytes). Formats without the GIL.";

PyObject *pk_py_csv_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3 || !PyTuple_Check(args[0])) {
        PyErr_SetString(PyExc_TypeError, "csv_rows(columns: tuple, start, stop)");
        return NULL;
    }
    Py_ssize_t start = PyLong_AsSsize_t(args[1]), stop = PyLong_AsSsize_t(args[2]);
    if (PyErr_Occurred()) return NULL;
    if (start < 0 || stop < start) {
        PyErr_SetString(PyExc_ValueError, "csv_rows: need 0 <= start <= stop");
        return NULL;
    }
    Py_ssize_t ncols = PyTuple_GET_SIZE(args[0]);
    if (ncols == 0) {
        PyErr_SetString(PyExc_ValueError, "csv_rows: no columns");
        return NULL;
    }
    Column *cols = PyMem_Calloc((size_t)ncols, sizeof(Column));
    if (!cols) return PyErr_NoMemory();
    PyObject *result = NULL;
    Py_ssize_t opened = 0, row_width = ncols; /* the commas and the line end */
    for (; opened < ncols; opened++) {
        if (open_column(PyTuple_GET_ITEM(args[0], opened), stop, cols + opened) < 0) {
            opened++;
            goto done;
        }
        row_width += cols[opened].width;
    }
    if (stop - start > PY_SSIZE_T_MAX / row_width) {
        PyErr_NoMemory();
        goto done;
    }
    result = PyBytes_FromStringAndSize(NULL, (stop - start) * row_width);
    if (!result) goto done;
    char *base = PyBytes_AS_STRING(result), *end;
    Py_BEGIN_ALLOW_THREADS
    end = format_rows(cols, ncols, start, stop, base);
    Py_END_ALLOW_THREADS
    if (!end) {
        Py_CLEAR(result);
        PyErr_SetString(PyExc_ValueError, "csv_rows: a code outside its labels");
        goto done;
    }
    _PyBytes_Resize(&result, end - base);
done:
    for (Py_ssize_t j = 0; j < opened; j++)
        if (cols[j].have_view) PyBuffer_Release(&cols[j].view);
    PyMem_Free(cols);
    return result;
}

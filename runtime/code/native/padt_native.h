/* What every C unit of the native tier includes (runtime/code/native/translate.py writes the
 * units). The units work on the runtime's own objects: a variable is the slot of a
 * generated class, read and written at its offset, so that every service of the runtime
 * (online values, forcing, reload, context) sees the same data as with the Python tier.
 *
 * Every helper that can fail sets a Python exception and returns -1 (or NULL); the unit
 * then adds its place in the generated code to the traceback, so that a fault names the
 * same ST line as in the Python tier.
 */
#ifndef PADT_NATIVE_H
#define PADT_NATIVE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>

#define PADT_LIKELY(x) __builtin_expect(!!(x), 1)
#define PADT_UNLIKELY(x) __builtin_expect(!!(x), 0)
#define PADT_SLOT(o, off) (*(PyObject **)((char *)(o) + (off)))

typedef __int128 padt_i128;

/* Loop passes between two looks at the interpreter's pending requests (padt_breathe). */
#define PADT_BREATH 4096

/* ---- state one module copy binds (padt_bind_common) ---------------------------------- */

/* Borrowed: each bound class holds the namespace (runtime/code/native/tier.py), and a body
 * runs as C only on an instance of its class; the classes are in the namespace. */
static PyObject *padt_ns;           /* the resource's namespace of generated code */
static PyObject *padt_breathe_fn;   /* a Python function of no code: see padt_breathe */
static PyObject *padt_str_call;     /* "__call__" */
static PyObject *padt_str_python_body; /* PYTHON_BODY_ATTR of runtime/code/native/tier.py */

/* A call site of `x.__call__()`: the type it last met, by version tag (no reference is
 * held, and a tag is never given to two types), and that type's native body. */
typedef struct {
    unsigned int tag;
    PyCFunction fn;
} padt_site;

static int
padt_bind_common(PyObject *ns, PyObject *breathe)
{
    if (!PyDict_Check(ns) || !PyCallable_Check(breathe)) {
        PyErr_SetString(PyExc_TypeError, "bind(namespace, breathe)");
        return -1;
    }
    padt_ns = ns;
    Py_XSETREF(padt_breathe_fn, Py_NewRef(breathe));
    if (padt_str_call == NULL && (padt_str_call = PyUnicode_InternFromString("__call__")) == NULL)
        return -1;
    if (padt_str_python_body == NULL
        && (padt_str_python_body = PyUnicode_InternFromString("python__call")) == NULL)
        return -1;
    return 0;
}

/* ---- the C stack ----------------------------------------------------------------------
 *
 * A block's body calls the bodies of the blocks it calls on the C stack, and IEC allows a
 * recursion (through a reference, an in-out): where it does not end, the Python tier
 * faults (RecursionError) while C would run off the end of its thread's stack and kill the
 * process. Each body therefore looks, as it begins, at how much of its thread's stack is
 * left: below the margin, a RecursionError, as the Python tier's. */
#define PADT_STACK_MARGIN (512 * 1024)

static _Thread_local char *padt_stack_low; /* this thread's stack's end, plus the margin */

static void
padt_stack_find(void)
{
    pthread_attr_t attr;
    void *low = NULL;
    size_t size = 0;
    if (pthread_getattr_np(pthread_self(), &attr) == 0) {
        if (pthread_attr_getstack(&attr, &low, &size) != 0)
            low = NULL;
        pthread_attr_destroy(&attr);
    }
    /* unknown (never on Linux): only the depth counters of FUNCTIONs remain */
    padt_stack_low = low != NULL && size > 2 * PADT_STACK_MARGIN
                         ? (char *)low + PADT_STACK_MARGIN
                         : (char *)1;
}

/* 0, or -1 with a RecursionError where the body's thread has little stack left (no frame
 * of the body's own on the traceback: the caller's line is the fault's, as Python's). */
static inline int
padt_stack_check(void)
{
    char here;
    if (PADT_UNLIKELY(padt_stack_low == NULL))
        padt_stack_find();
    if (PADT_LIKELY(&here > padt_stack_low))
        return 0;
    PyErr_SetString(PyExc_RecursionError, "maximum recursion depth exceeded in native code");
    return -1;
}

/* ---- FUNCTIONs' C bodies (function_body.py) -------------------------------------------
 *
 * A FUNCTION of numbers and BOOLs has a C body, `int F(padt_mctx *ctx, <its parameters>,
 * <a pointer per result and output>)` (ctx NULL in slot mode), which its module puts into
 * the binding's table of FUNCTIONs by its name and C signature: a call site made for
 * another signature never finds it. A call site looks once; where the FUNCTION has no C
 * body (it stays Python), it calls the Python. */
#define PADT_FUNCTION_CAPSULE "padt_function"

static PyObject *padt_functions; /* key -> capsule of a C body (borrowed, as padt_ns) */

typedef struct {
    void *function;
    int looked;
} padt_fsite;

static int
padt_bind_functions(PyObject *functions)
{
    if (!PyDict_Check(functions)) {
        PyErr_SetString(PyExc_TypeError, "native code: the FUNCTIONs' table is no dict");
        return -1;
    }
    padt_functions = functions;
    return 0;
}

static int
padt_register_function(const char *key, void *function)
{
    PyObject *capsule = PyCapsule_New(function, PADT_FUNCTION_CAPSULE, NULL);
    if (capsule == NULL)
        return -1;
    int failed = PyDict_SetItemString(padt_functions, key, capsule);
    Py_DECREF(capsule);
    return failed;
}

static inline int
padt_function_site(padt_fsite *site, PyObject *key)
{
    if (PADT_LIKELY(site->looked))
        return 0;
    PyObject *capsule = PyDict_GetItemWithError(padt_functions, key);
    if (capsule == NULL && PyErr_Occurred())
        return -1;
    if (capsule != NULL
        && (site->function = PyCapsule_GetPointer(capsule, PADT_FUNCTION_CAPSULE)) == NULL)
        return -1;
    site->looked = 1;
    return 0;
}

/* The offset of slot `name` of `type` (a __slots__ member), or -1 with an exception. */
static Py_ssize_t
padt_offset(PyObject *type, const char *name)
{
    if (!PyType_Check(type)) {
        PyErr_Format(PyExc_TypeError, "native code: %R is no class", type);
        return -1;
    }
    PyObject *key = PyUnicode_InternFromString(name);
    if (key == NULL)
        return -1;
    PyObject *descr = _PyType_Lookup((PyTypeObject *)type, key);
    Py_DECREF(key);
    if (descr == NULL || !Py_IS_TYPE(descr, &PyMemberDescr_Type)
        || ((PyMemberDescrObject *)descr)->d_member->type != T_OBJECT_EX) {
        PyErr_Format(PyExc_TypeError, "native code: %R has no slot %s", type, name);
        return -1;
    }
    return ((PyMemberDescrObject *)descr)->d_member->offset;
}

/* A class of the namespace by name, borrowed (the namespace keeps it). */
static PyObject *
padt_class(const char *name)
{
    PyObject *found = PyDict_GetItemString(padt_ns, name);
    if (found == NULL || !PyType_Check(found)) {
        PyErr_Format(PyExc_TypeError, "native code: no class %s", name);
        return NULL;
    }
    return found;
}

/* ---- values ---------------------------------------------------------------------------
 *
 * The contract (runtime/contract/values.py) keeps every stored value in the range of its
 * type, and the translator's proofs rest on it, as the generated Python's wrapping does.
 * What a read checks is what memory safety needs: the slot holds an object of the right
 * type. Anything else jumps to the body's `padt_bad`, a fault at that line.
 */

#if PY_VERSION_HEX >= 0x030C0000
#define PADT_SMALL(o) PyUnstable_Long_IsCompact((PyLongObject *)(o))
#define PADT_SMALL_VALUE(o) ((int64_t)PyUnstable_Long_CompactValue((PyLongObject *)(o)))
#else
/* one 30-bit digit (or none): the value is the sign times that digit */
#define PADT_SMALL(o) ((size_t)(Py_SIZE(o) + 1) <= 2)
#define PADT_SMALL_VALUE(o) (Py_SIZE(o) * (int64_t)((PyLongObject *)(o))->ob_digit[0])
#endif

/* An integer of a type whose values fit one digit (SINT, INT, UINT, BYTE, WORD...). */
#define PADT_GET_SMALL(o, out)                                                            \
    do {                                                                                  \
        PyObject *padt_o_ = (o);                                                          \
        if (PADT_UNLIKELY(padt_o_ == NULL || !Py_IS_TYPE(padt_o_, &PyLong_Type)          \
                          || !PADT_SMALL(padt_o_)))                                       \
            goto padt_bad;                                                                \
        (out) = PADT_SMALL_VALUE(padt_o_);                                                \
    } while (0)

/* An integer of at most 64 bits (DINT, LINT, TIME, UDINT...). */
#define PADT_GET_INT(o, out)                                                              \
    do {                                                                                  \
        PyObject *padt_o_ = (o);                                                          \
        if (PADT_UNLIKELY(padt_o_ == NULL || !Py_IS_TYPE(padt_o_, &PyLong_Type)))         \
            goto padt_bad;                                                                \
        if (PADT_LIKELY(PADT_SMALL(padt_o_)))                                             \
            (out) = PADT_SMALL_VALUE(padt_o_);                                            \
        else if (padt_int_slow(padt_o_, &(out)) < 0)                                      \
            goto padt_bad;                                                                \
    } while (0)

/* An integer of ULINT or LWORD (0..2**64-1), into a padt_i128: a negative one or one
 * beyond 64 bits (which no checked writer stores) is a fault like a value of another type. */
#define PADT_GET_U64(o, out)                                                              \
    do {                                                                                  \
        PyObject *padt_o_ = (o);                                                          \
        if (PADT_UNLIKELY(padt_o_ == NULL || !Py_IS_TYPE(padt_o_, &PyLong_Type)))         \
            goto padt_bad;                                                                \
        if (PADT_LIKELY(PADT_SMALL(padt_o_) && PADT_SMALL_VALUE(padt_o_) >= 0))           \
            (out) = PADT_SMALL_VALUE(padt_o_);                                            \
        else if (padt_u64_slow(padt_o_, &(out)) < 0)                                      \
            goto padt_bad;                                                                \
    } while (0)

#define PADT_GET_BOOL(o, out)                                                             \
    do {                                                                                  \
        PyObject *padt_o_ = (o);                                                          \
        if (padt_o_ == Py_True)                                                           \
            (out) = 1;                                                                    \
        else if (PADT_LIKELY(padt_o_ == Py_False))                                        \
            (out) = 0;                                                                    \
        else                                                                              \
            goto padt_bad;                                                                \
    } while (0)

#define PADT_GET_FLOAT(o, out)                                                            \
    do {                                                                                  \
        PyObject *padt_o_ = (o);                                                          \
        if (PADT_UNLIKELY(padt_o_ == NULL || !PyFloat_CheckExact(padt_o_)))               \
            goto padt_bad;                                                                \
        (out) = PyFloat_AS_DOUBLE(padt_o_);                                               \
    } while (0)

/* An instance of a generated class (or of one that extends it). */
#define PADT_CHECK_INSTANCE(o, type)                                                      \
    do {                                                                                  \
        if (PADT_UNLIKELY((o) == NULL || !PyObject_TypeCheck((o), (PyTypeObject *)(type)))) \
            goto padt_bad;                                                                \
    } while (0)

#define PADT_CHECK_TEXT(o)                                                                \
    do {                                                                                  \
        if (PADT_UNLIKELY((o) == NULL || !PyUnicode_CheckExact(o)))                       \
            goto padt_bad;                                                                \
    } while (0)

#define PADT_CHECK_TUPLE(o, n)                                                            \
    do {                                                                                  \
        if (PADT_UNLIKELY((o) == NULL || !PyTuple_CheckExact(o) || PyTuple_GET_SIZE(o) != (n))) \
            goto padt_bad;                                                                \
    } while (0)

/* A reference: None (NULL) or the runtime's Reference, a str (its helpers check the rest) */
#define PADT_CHECK_REF(o)                                                                 \
    do {                                                                                  \
        if (PADT_UNLIKELY((o) == NULL || ((o) != Py_None && !PyUnicode_Check(o))))        \
            goto padt_bad;                                                                \
    } while (0)

#define PADT_CHECK_LIST(o)                                                                \
    do {                                                                                  \
        if (PADT_UNLIKELY((o) == NULL || !PyList_CheckExact(o)))                          \
            goto padt_bad;                                                                \
    } while (0)

static int
padt_int_slow(PyObject *o, int64_t *out)
{
    int overflow = 0;
    long long v = PyLong_AsLongLongAndOverflow(o, &overflow);
    if (overflow || (v == -1 && PyErr_Occurred())) {
        PyErr_Clear();
        return -1;
    }
    *out = v;
    return 0;
}

static int
padt_u64_slow(PyObject *o, padt_i128 *out)
{
    unsigned long long v = PyLong_AsUnsignedLongLong(o);
    if (v == (unsigned long long)-1 && PyErr_Occurred()) {
        PyErr_Clear();
        return -1;
    }
    *out = (padt_i128)v;
    return 0;
}

/* The fault of a read that found a value of another type. */
static void
padt_bad_read(void)
{
    if (!PyErr_Occurred())
        PyErr_SetString(PyExc_TypeError,
                        "native code: a variable holds a value of another type than declared");
}

/* An offset into a list as Python reads `l[i]`: a negative index counts from the end. */
static inline int
padt_index(PyObject *list, int64_t i, Py_ssize_t *out)
{
    Py_ssize_t n = PyList_GET_SIZE(list);
    if (i < 0)
        i += n;
    if (PADT_LIKELY(i >= 0 && i < n)) {
        *out = (Py_ssize_t)i;
        return 0;
    }
    PyErr_SetString(PyExc_IndexError, "list index out of range");
    return -1;
}

static PyObject *
padt_box128(padt_i128 v)
{
    if (v >= INT64_MIN && v <= INT64_MAX)
        return PyLong_FromLongLong((long long)v);
    if (v > 0 && v <= (padt_i128)UINT64_MAX) /* a ULINT or LWORD beyond 2**63 */
        return PyLong_FromUnsignedLongLong((unsigned long long)v);
    return _PyLong_FromByteArray((const unsigned char *)&v, sizeof v, 1, 1);
}

static int
padt_put(PyObject **place, PyObject *value)
{
    if (value == NULL)
        return -1;
    PyObject *old = *place;
    *place = value;
    Py_XDECREF(old);
    return 0;
}

/* Store an integer. An int object that only this place holds (a reference count of one)
 * takes the new value in place when both have one digit: no allocation, no freeing, and
 * nothing else can tell, since nothing else refers to it (the interpreter lock is held).
 * The shared small ints (-5..256) are never changed. */
static inline int
padt_set_int(PyObject **place, int64_t v)
{
#if PY_VERSION_HEX < 0x030C0000
    PyObject *old = *place;
    if (PADT_LIKELY(old != NULL && Py_REFCNT(old) == 1 && Py_IS_TYPE(old, &PyLong_Type)
                    && (Py_SIZE(old) == 1 || Py_SIZE(old) == -1)
                    && (v > 256 || v < -5) && v < (1 << 30) && v > -(1 << 30))) {
        Py_SET_SIZE(old, v < 0 ? -1 : 1);
        ((PyLongObject *)old)->ob_digit[0] = (digit)(v < 0 ? -v : v);
        return 0;
    }
#endif
    return padt_put(place, PyLong_FromLongLong((long long)v));
}

static inline int
padt_set_int128(PyObject **place, padt_i128 v)
{
    if (v >= INT64_MIN && v <= INT64_MAX)
        return padt_set_int(place, (int64_t)v);
    return padt_put(place, padt_box128(v));
}

/* Store a REAL: in place into a float object only this place holds, as padt_set_int. */
static inline int
padt_set_float(PyObject **place, double v)
{
    PyObject *old = *place;
    if (PADT_LIKELY(old != NULL && Py_REFCNT(old) == 1 && PyFloat_CheckExact(old))) {
        ((PyFloatObject *)old)->ob_fval = v;
        return 0;
    }
    return padt_put(place, PyFloat_FromDouble(v));
}

/* runtime.code.intrinsics._fdiv: IEC division of REALs, by zero an infinity or NaN, no fault */
static inline double
padt_fdiv(double a, double b)
{
    if (PADT_UNLIKELY(b == 0.0)) {
        if (a == 0.0 || isnan(a))
            return __builtin_nan("");
        return copysign(__builtin_inf(), a) * copysign(1.0, b);
    }
    return a / b;
}

/* runtime.code.intrinsics._safe_math: a function of libm as Python's math module calls it,
 * NaN where Python raises (a NaN of a number, or an infinity of a finite one: out of the
 * domain, or an overflow). */
static inline double
padt_safe_math(double (*function)(double), double x)
{
    double r = function(x);
    if ((isnan(r) && !isnan(x)) || (isinf(r) && isfinite(x)))
        return __builtin_nan("");
    return r;
}

/* `text[:stop]`, a new reference: the text itself where it is no longer. */
static inline PyObject *
padt_cut(PyObject *text, Py_ssize_t stop)
{
    if (PyUnicode_GET_LENGTH(text) <= stop)
        return Py_NewRef(text);
    return PyUnicode_Substring(text, 0, stop);
}

/* runtime.code.intrinsics._pow (EXPT), as Python's power of floats computes it (on the
 * magnitude of a negative base, the sign put back for an odd power), with the helper's
 * +inf where Python raises (zero to a negative power, an overflow) and NaN where Python's
 * result is a complex number (a negative base to a power that is no whole number). */
static inline double
padt_pow(double a, double b)
{
    if (b == 0.0)
        return 1.0;
    if (isnan(a))
        return a;
    if (isnan(b))
        return a == 1.0 ? 1.0 : b;
    if (isinf(b)) {
        a = fabs(a);
        if (a == 1.0)
            return 1.0;
        return (a > 1.0) == (b > 0.0) ? __builtin_inf() : 0.0;
    }
    int odd = fmod(fabs(b), 2.0) == 1.0;
    if (isinf(a))
        return b > 0.0 ? (odd ? a : fabs(a)) : (odd ? copysign(0.0, a) : 0.0);
    if (a == 0.0)
        return b < 0.0 ? __builtin_inf() : (odd ? a : 0.0);
    int negate = 0;
    if (a < 0.0) {
        if (b != floor(b))
            return __builtin_nan("");
        a = -a;
        negate = odd;
    }
    if (a == 1.0)
        return negate ? -1.0 : 1.0;
    double r = pow(a, b);
    if (isinf(r))
        return __builtin_inf();
    return negate ? -r : r;
}

/* runtime.code.intrinsics._rol and _ror: a value within `bits` (1..63) rotated by n modulo
 * the width (Python's modulo: never negative). */
static inline int64_t
padt_rol(int64_t value, int64_t n, int bits)
{
    uint64_t v = (uint64_t)value, mask = (UINT64_C(1) << bits) - 1;
    int64_t k = n % bits;
    if (k < 0)
        k += bits;
    if (k == 0)
        return (int64_t)(v & mask);
    return (int64_t)(((v << k) | (v >> (bits - k))) & mask);
}

static inline int64_t
padt_ror(int64_t value, int64_t n, int bits)
{
    int64_t k = n % bits;
    if (k < 0)
        k += bits;
    return padt_rol(value, bits - k, bits);
}

/* The same over 64 bits (LWORD): a value within 0..2**64-1, as a padt_i128. */
static inline padt_i128
padt_rol64(padt_i128 value, int64_t n)
{
    uint64_t v = (uint64_t)value;
    int64_t k = n % 64;
    if (k < 0)
        k += 64;
    if (k == 0) /* a shift by 64 bits is undefined in C */
        return (padt_i128)v;
    return (padt_i128)((v << k) | (v >> (64 - k)));
}

static inline padt_i128
padt_ror64(padt_i128 value, int64_t n)
{
    int64_t k = n % 64;
    if (k < 0)
        k += 64;
    return padt_rol64(value, 64 - k);
}

/* An integer within +-(2**64-1) as Python converts it to a float: the nearest double, ties
 * to even, which C's conversion of its magnitude (an unsigned 64-bit integer) is, and
 * rounding to the nearest is the same for either sign. */
static inline double
padt_double_wide(padt_i128 v)
{
    return v < 0 ? -(double)(uint64_t)(-v) : (double)(uint64_t)v;
}

/* A REAL taken to an integer (runtime/code/native/kinds.py, Int.stand_in): exact below 2**126;
 * beyond, a stand-in of that size that equals the true value modulo 2**64 (fmod is exact),
 * which is all a wrap to at most 64 bits keeps of it. */
#define PADT_TWO_126 85070591730234615865843651857942052864.0
#define PADT_TWO_64 18446744073709551616.0

static inline padt_i128
padt_whole(double whole) /* a non-negative integral double */
{
    if (PADT_LIKELY(whole < PADT_TWO_126))
        return (padt_i128)whole;
    return ((padt_i128)1 << 126) + (padt_i128)(uint64_t)fmod(whole, PADT_TWO_64);
}

/* An int of any size (the result of a helper such as STRING_TO_INT's, which a wrap takes
 * to at most 64 bits at once): exact within 2**126, beyond a stand-in as padt_whole makes
 * one, of that size and equal to the true value modulo 2**64. */
static int
padt_any_int(PyObject *o, padt_i128 *out)
{
    unsigned char bytes[16];
    if (_PyLong_AsByteArray((PyLongObject *)o, bytes, sizeof bytes, 1, 1) == 0) {
        unsigned __int128 bits = 0;
        for (int i = (int)sizeof bytes - 1; i >= 0; i--)
            bits = (bits << 8) | bytes[i];
        padt_i128 v = (padt_i128)bits;
        if (v > -((padt_i128)1 << 126) && v < ((padt_i128)1 << 126)) {
            *out = v;
            return 0;
        }
    } else if (!PyErr_ExceptionMatches(PyExc_OverflowError)) {
        return -1;
    }
    PyErr_Clear();
    PyObject *magnitude = PyNumber_Absolute(o);
    if (magnitude == NULL)
        return -1;
    uint64_t low = PyLong_AsUnsignedLongLongMask(magnitude);
    Py_DECREF(magnitude);
    if (low == (uint64_t)-1 && PyErr_Occurred())
        return -1;
    padt_i128 stand_in = ((padt_i128)1 << 126) + (padt_i128)low;
    *out = _PyLong_Sign(o) < 0 ? -stand_in : stand_in;
    return 0;
}

/* runtime.code.intrinsics._round: to the nearest, halves away from zero; NaN and infinities 0 */
static inline int
padt_round(double x, padt_i128 *out)
{
    if (!isfinite(x)) {
        *out = 0;
        return 0;
    }
    double magnitude = fabs(x);
    double whole = floor(magnitude);
    if (magnitude - whole >= 0.5) /* exact, as in the helper */
        whole += 1.0;
    *out = x >= 0 ? padt_whole(whole) : -padt_whole(whole);
    return 0;
}

/* int(x) of a REAL: toward zero; NaN and infinities raise what Python's int() raises */
static inline int
padt_trunc(double x, padt_i128 *out)
{
    if (PADT_UNLIKELY(!isfinite(x))) {
        PyObject *number = PyFloat_FromDouble(x);
        PyObject *whole = number != NULL ? PyNumber_Long(number) : NULL;
        Py_XDECREF(number);
        Py_XDECREF(whole);
        if (whole != NULL)
            PyErr_SetString(PyExc_SystemError, "native code: int() of a non-finite REAL");
        return -1;
    }
    double whole = floor(fabs(x));
    *out = x >= 0 ? padt_whole(whole) : -padt_whole(whole);
    return 0;
}

static inline void
padt_set_bool(PyObject **place, int v)
{
    PyObject *value = v ? Py_True : Py_False;
    PyObject *old = *place;
    Py_INCREF(value);
    *place = value;
    Py_XDECREF(old);
}

#define PADT_PLACE(o, off) ((PyObject **)((char *)(o) + (off)))
#define PADT_ITEM_PLACE(list, i) (&PyList_GET_ITEM((list), (i)))

/* A 128-bit intermediate that a local of 64 bits must take. */
static inline int
padt_narrow(padt_i128 v, int64_t *out)
{
    if (PADT_LIKELY(v >= INT64_MIN && v <= INT64_MAX)) {
        *out = (int64_t)v;
        return 0;
    }
    PyErr_SetString(PyExc_OverflowError, "native code: an integer beyond 64 bits");
    return -1;
}

/* A value proven nowhere to fit the variable it is stored into: the contract keeps it in
 * range, and a value outside is a fault rather than a silent difference. */
static inline int
padt_in_range(padt_i128 v, padt_i128 lo, padt_i128 hi, const char *what)
{
    if (PADT_LIKELY(lo <= v && v <= hi))
        return 0;
    PyErr_Format(PyExc_OverflowError, "native code: a value outside the range of %s", what);
    return -1;
}

/* ---- names of the namespace ----------------------------------------------------------- */

/* A name of the namespace (`_tick`, `_G`), borrowed; None when absent. */
static inline PyObject *
padt_global(PyObject *key)
{
    PyObject *found = PyDict_GetItemWithError(padt_ns, key);
    if (found == NULL && !PyErr_Occurred())
        return Py_None;
    return found;
}

/* A helper of the namespace (`_ix`, `_idiv`) called with `args` (a new tuple, taken; NULL:
 * an error already set) to raise its own error, so that the fault is the one the Python
 * tier raises. */
static int
padt_raise_with(const char *helper, PyObject *args)
{
    PyObject *fn = PyDict_GetItemString(padt_ns, helper);
    if (fn == NULL) {
        Py_XDECREF(args);
        PyErr_Format(PyExc_SystemError, "native code: no %s", helper);
        return -1;
    }
    if (args == NULL)
        return -1;
    PyObject *result = PyObject_Call(fn, args, NULL);
    Py_DECREF(args);
    if (result == NULL)
        return -1;
    Py_DECREF(result);
    PyErr_Format(PyExc_SystemError, "native code: %s did not raise", helper);
    return -1;
}

/* The same with two or three 64-bit integers. */
static int
padt_raise_through(const char *helper, int n, int64_t a, int64_t b, int64_t c)
{
    return padt_raise_with(helper, n == 2 ? Py_BuildValue("(LL)", (long long)a, (long long)b)
                                          : Py_BuildValue("(LLL)", (long long)a, (long long)b,
                                                          (long long)c));
}

/* IEC division of integers: toward zero; by zero, the Python helper's fault. */
static inline int
padt_idiv(int64_t a, int64_t b, int64_t *out)
{
    if (PADT_UNLIKELY(b == 0))
        return padt_raise_through("_idiv", 2, a, b, 0);
    if (PADT_UNLIKELY(b == -1)) /* INT64_MIN / -1 */
        *out = (int64_t)(0 - (uint64_t)a);
    else
        *out = a / b;
    return 0;
}

/* The same, where the quotient may be 2**63 (the smallest 64-bit integer by -1). */
static inline int
padt_idiv128(int64_t a, int64_t b, padt_i128 *out)
{
    if (PADT_UNLIKELY(b == 0))
        return padt_raise_through("_idiv", 2, a, b, 0);
    *out = (padt_i128)a / b;
    return 0;
}

static inline int
padt_imod(int64_t a, int64_t b, int64_t *out)
{
    if (PADT_UNLIKELY(b == 0))
        return padt_raise_through("_imod", 2, a, b, 0);
    *out = b == -1 ? 0 : a % b;
    return 0;
}

/* The same for operands beyond 64 bits (ULINT, LWORD): by zero, the helper's fault, called
 * with the operands as Python has them. The translator keeps both within +-2**127 and
 * the quotient too (never the smallest 128-bit integer by -1). */
static int
padt_raise_through128(const char *helper, padt_i128 a, padt_i128 b)
{
    PyObject *x = padt_box128(a), *y = x != NULL ? padt_box128(b) : NULL;
    PyObject *args = y != NULL ? PyTuple_Pack(2, x, y) : NULL;
    Py_XDECREF(x);
    Py_XDECREF(y);
    return padt_raise_with(helper, args);
}

static inline int
padt_idiv_wide(padt_i128 a, padt_i128 b, padt_i128 *out)
{
    if (PADT_UNLIKELY(b == 0))
        return padt_raise_through128("_idiv", a, b);
    *out = a / b; /* toward zero, as the helper */
    return 0;
}

static inline int
padt_imod_wide(padt_i128 a, padt_i128 b, padt_i128 *out)
{
    if (PADT_UNLIKELY(b == 0))
        return padt_raise_through128("_imod", a, b);
    *out = a % b; /* a - b * (a / b), the sign of a, as the helper */
    return 0;
}

/* ---- calls and loops ------------------------------------------------------------------ */

static PyObject *
padt_call_slow(PyObject *o, padt_site *site)
{
    PyTypeObject *type = Py_TYPE(o);
    PyObject *method = _PyType_Lookup(type, padt_str_call);
    if (method != NULL && Py_IS_TYPE(method, &PyMethodDescr_Type)
        && ((PyMethodDescrObject *)method)->d_method->ml_flags == METH_NOARGS
        && (type->tp_flags & Py_TPFLAGS_VALID_VERSION_TAG) && type->tp_version_tag != 0) {
        site->tag = type->tp_version_tag;
        site->fn = ((PyMethodDescrObject *)method)->d_method->ml_meth;
        return site->fn(o, NULL);
    }
    return PyObject_CallMethodNoArgs(o, padt_str_call);
}

/* `o.__call__()`: straight into a native body, else through Python. */
static inline int
padt_call(PyObject *o, padt_site *site)
{
    PyObject *result = PADT_LIKELY(Py_TYPE(o)->tp_version_tag == site->tag && site->tag != 0)
                           ? site->fn(o, NULL)
                           : padt_call_slow(o, site);
    if (result == NULL)
        return -1;
    Py_DECREF(result);
    return 0;
}

/* Calling a Python function of no code makes the interpreter look at its pending
 * requests, as it does at the back edge of a loop in Python: another thread's turn for
 * the interpreter lock, and the watchdog's asynchronous exception, raised here. */
static int
padt_breathe(void)
{
    PyObject *result = PyObject_CallNoArgs(padt_breathe_fn);
    if (result == NULL)
        return -1;
    Py_DECREF(result);
    return 0;
}

/* A FUNCTION of the namespace, called as generated Python calls it (`nargs` positional
 * values, then the keywords `kwnames` names): its result, or NULL with the error set. */
static PyObject *
padt_call_function(PyObject *key, PyObject *const *args, size_t nargs, PyObject *kwnames)
{
    PyObject *function = padt_global(key);
    if (function == NULL)
        return NULL;
    return PyObject_Vectorcall(function, args, nargs, kwnames);
}

/* A method of `args[0]`, looked up on it as Python looks it up (an override included). */
static inline PyObject *
padt_call_method(PyObject *name, PyObject *const *args, size_t nargs, PyObject *kwnames)
{
    return PyObject_VectorcallMethod(name, args, nargs, kwnames);
}

/* A method as the class `cls` has it, not the instance's (SUPER^.X(): args[0] is the
 * instance, of a class derived from cls). */
static inline PyObject *
padt_call_in_class(PyObject *cls, PyObject *name, PyObject *const *args, size_t nargs,
                   PyObject *kwnames)
{
    PyObject *function = PyObject_GetAttr(cls, name);
    if (function == NULL)
        return NULL;
    PyObject *result = PyObject_Vectorcall(function, args, nargs, kwnames);
    Py_DECREF(function);
    return result;
}

#define PADT_BOOL_OBJECT(v) Py_NewRef((v) ? Py_True : Py_False)

static int
padt_call_any(PyObject *callable)
{
    PyObject *result = PyObject_CallNoArgs(callable);
    if (result == NULL)
        return -1;
    Py_DECREF(result);
    return 0;
}

/* ---- binding a body to its class ------------------------------------------------------ */

/* A body called on an object that is not an instance of its class: a derived block's
 * SUPER^() runs its base's body on its own instance, whose class has slots of its own
 * (generated classes do not inherit). The C body knows the slots of its class only; the
 * Python body, which the tier keeps on the class, reads them by name. */
static PyObject *
padt_python_body(PyObject *type, PyObject *o)
{
    PyObject *body = _PyType_Lookup((PyTypeObject *)type, padt_str_python_body);
    if (body == NULL) {
        PyErr_Format(PyExc_TypeError, "native code: %R has no Python body for %R", type,
                     Py_TYPE(o));
        return NULL;
    }
    Py_INCREF(body);
    PyObject *result = PyObject_CallOneArg(body, o);
    Py_DECREF(body);
    return result;
}

/* The body as the class's `__call__`, in a dict the binding sets on the class: a method
 * descriptor of `object`, so that it takes any instance (Python code calls
 * `POU_BASE.__call__(s)` with the derived block's `s`); the function it wraps checks the
 * class itself (translate.py) and hands any other instance to padt_python_body. */
static int
padt_add_method_of(PyObject *bodies, const char *class_name, PyMethodDef *def,
                   PyTypeObject *owner)
{
    PyObject *descr = PyDescr_NewMethod(owner, def);
    if (descr == NULL)
        return -1;
    PyObject *key = Py_BuildValue("(ss)", class_name, def->ml_name);
    int failed = key == NULL || PyDict_SetItem(bodies, key, descr) < 0;
    Py_XDECREF(key);
    Py_DECREF(descr);
    return failed ? -1 : 0;
}

static int
padt_add_method(PyObject *bodies, const char *class_name, PyMethodDef *def)
{
    if (padt_class(class_name) == NULL)
        return -1;
    return padt_add_method_of(bodies, class_name, def, &PyBaseObject_Type);
}

/* ---- bodies on a memory image (translate.py's image mode) -----------------------------
 *
 * A body of image mode takes the address of its instance's bytes in the image and the
 * context of the call: the image, where it begins, and where the globals the running
 * program sees begin (from `_G`, a view). It returns 0, or -1 with the exception set. A
 * block's call goes to the callee's C body through the registry of bodies (a class name's
 * capsule), or, for a body left to Python, to the `__call__` of a view of the callee.
 */
#include "padt_image.h"

typedef struct padt_mctx {
    PyObject *image; /* borrowed: the view the call began with holds it */
    char *base;
    Py_ssize_t size; /* of the image, which never changes its size */
    char *g; /* NULL: `_G` is no view of this image */
    PyObject *sys; /* `_SYS`, borrowed from the namespace (NULL: none) */
    int now_known; /* `_SYS.now_ns` read in this call (padt_mnow) */
    int64_t now_ns;
    int tick_known; /* `_tick` read in this call (padt_mtick) */
    PyObject *tick; /* borrowed: the namespace holds it */
    int depth; /* C FUNCTION and method calls nested in this call (padt_enter) */
} padt_mctx;

/* Nested C calls of FUNCTIONs and methods (function_body.py), each on the C stack: a
 * recursion (which IEC allows) is a RecursionError beyond Python's default recursion
 * limit, as on the Python tier, never the stack's end. */
#define PADT_MAX_DEPTH 1000

/* A C FUNCTION's or method's entry: -1 with a RecursionError where calls nest too deep
 * (no frame of its own on the traceback: the caller's line is the fault's, as Python's). */
static inline int
padt_enter(padt_mctx *ctx)
{
    if (PADT_LIKELY(++ctx->depth <= PADT_MAX_DEPTH))
        return 0;
    ctx->depth--;
    PyErr_SetString(PyExc_RecursionError, "maximum recursion depth exceeded in native code");
    return -1;
}

typedef int (*padt_mbody)(char *, padt_mctx *);

/* A call site of a block's body: the C body, once found, or the view class to call. */
typedef struct {
    padt_mbody body;
    PyObject *view_type; /* borrowed: padt_views holds it */
} padt_msite;

static PyObject *padt_views;        /* class name -> view class (borrowed) */
static PyObject *padt_registry;     /* class name -> capsule of its C body (borrowed) */
static PyTypeObject *padt_view_type; /* padt_memory.View (borrowed) */
static PyObject *padt_str_g;        /* "_G" */
static PyObject *padt_str_sys;      /* "_SYS" */

#define PADT_BODY_CAPSULE "padt_body"

static int
padt_bind_image(PyObject *views, PyObject *registry, PyObject *view_type)
{
    if (!PyDict_Check(views) || !PyDict_Check(registry) || !PyType_Check(view_type)) {
        PyErr_SetString(PyExc_TypeError, "bind(namespace, breathe, views, registry, View)");
        return -1;
    }
    /* borrowed, as the namespace: each bound view class holds them (tier.py), so the
     * module copy is free again once its classes are gone */
    padt_views = views;
    padt_registry = registry;
    padt_view_type = (PyTypeObject *)view_type;
    if (padt_bind_functions(registry) < 0) /* the FUNCTIONs' C bodies beside the blocks' */
        return -1;
    if (padt_str_g == NULL && (padt_str_g = PyUnicode_InternFromString("_G")) == NULL)
        return -1;
    if (padt_str_sys == NULL && (padt_str_sys = PyUnicode_InternFromString("_SYS")) == NULL)
        return -1;
    return 0;
}

/* A body into the registry, for the calls of other modules. */
static int
padt_register(const char *class_name, padt_mbody body)
{
    PyObject *capsule = PyCapsule_New((void *)body, PADT_BODY_CAPSULE, NULL);
    if (capsule == NULL)
        return -1;
    int failed = PyDict_SetItemString(padt_registry, class_name, capsule);
    Py_DECREF(capsule);
    return failed;
}

/* The context of a call that begins at `view`. */
static int
padt_mctx_enter(padt_mctx *ctx, PyObject *view)
{
    padt_view *v = (padt_view *)view;
    ctx->image = v->image;
    ctx->base = PyByteArray_AS_STRING(v->image);
    ctx->size = PyByteArray_GET_SIZE(v->image);
    ctx->g = NULL;
    ctx->now_known = 0;
    ctx->tick_known = 0;
    ctx->depth = 0;
    ctx->sys = PyDict_GetItemWithError(padt_ns, padt_str_sys);
    if (ctx->sys == NULL && PyErr_Occurred())
        return -1;
    PyObject *g = PyDict_GetItemWithError(padt_ns, padt_str_g);
    if (g == NULL)
        return PyErr_Occurred() ? -1 : 0;
    if (PyObject_TypeCheck(g, padt_view_type) && ((padt_view *)g)->image == v->image)
        ctx->g = ctx->base + ((padt_view *)g)->offset;
    return 0;
}

/* `_tick`: the slice meter, or None where loop passes are not metered. The scheduler sets
 * it between program cycles and slices only, so it is read once per call (every loop
 * reads it), and again after the meter's call (the body clears tick_known), which may
 * resume the program in a later slice. Borrowed, as `padt_global` gives it. */
static inline PyObject *
padt_mtick(padt_mctx *ctx, PyObject *key)
{
    if (PADT_LIKELY(ctx->tick_known))
        return ctx->tick;
    PyObject *tick = padt_global(key);
    if (tick != NULL) {
        ctx->tick = tick;
        ctx->tick_known = 1;
    }
    return tick;
}

/* `_SYS.now_ns`: the running program's time, which the scheduler sets between program
 * cycles, read once per call (each timer of a program reads it), and again after the
 * slice meter (the body clears now_known), which may resume the program in a later CPU
 * cycle. */
static int
padt_mnow(padt_mctx *ctx, PyObject *sys, PyObject *key, int64_t *out)
{
    if (PADT_LIKELY(ctx->now_known)) {
        *out = ctx->now_ns;
        return 0;
    }
    PyObject *now = PyObject_GetAttr(sys, key);
    if (now == NULL)
        return -1;
    int overflow = 0, is_int = PyLong_Check(now);
    long long value = is_int ? PyLong_AsLongLongAndOverflow(now, &overflow) : -1;
    Py_DECREF(now);
    if (!is_int || overflow || (value == -1 && PyErr_Occurred())) {
        if (!PyErr_Occurred())
            padt_bad_read();
        return -1;
    }
    ctx->now_ns = value;
    ctx->now_known = 1;
    *out = value;
    return 0;
}

static int
padt_mcall(padt_msite *site, PyObject *class_name, char *p, padt_mctx *ctx)
{
    if (PADT_LIKELY(site->body != NULL))
        return site->body(p, ctx);
    if (site->view_type == NULL) {
        PyObject *capsule = PyDict_GetItemWithError(padt_registry, class_name);
        if (capsule != NULL) {
            site->body = (padt_mbody)PyCapsule_GetPointer(capsule, PADT_BODY_CAPSULE);
            return site->body == NULL ? -1 : site->body(p, ctx);
        }
        if (PyErr_Occurred())
            return -1;
        site->view_type = PyDict_GetItemWithError(padt_views, class_name);
        if (site->view_type == NULL) {
            if (!PyErr_Occurred())
                PyErr_Format(PyExc_TypeError, "native code: no view class %R", class_name);
            return -1;
        }
    }
    PyObject *view = PyObject_CallFunction(site->view_type, "On", ctx->image,
                                           (Py_ssize_t)(p - ctx->base));
    if (view == NULL)
        return -1;
    PyObject *result = PyObject_CallMethodNoArgs(view, padt_str_call);
    Py_DECREF(view);
    if (result == NULL)
        return -1;
    Py_DECREF(result);
    return 0;
}

/* The runtime's SFC classes in the image (runtime/contract/layout.py's fixed layouts; each
 * module asserts the offsets its layouts give): a time that is None in Python is
 * INT64_MIN. What their Python methods do (runtime/code/intrinsics.py: _step_time,
 * _step_enter, _ActionControl.update), on the bytes. */
#define PADT_NO_TIME INT64_MIN

typedef struct {
    uint8_t X;
    int64_t T;
    int64_t since;
} padt_sfc_step;

typedef struct {
    uint8_t A, Q, held, stored, sd_set, ds_stored, sl_set, p_prev, p1_prev, p0_prev;
    int64_t l_since, d_since, sd_since, ds_since, sl_since;
} padt_action_control;

static inline int64_t
padt_step_time(char *p, int64_t now)
{
    padt_sfc_step *step = (padt_sfc_step *)p;
    if (step->since == PADT_NO_TIME) /* the first cycle in which the step is active */
        step->since = now;
    return now - step->since;
}

static inline void
padt_step_enter(char *p)
{
    padt_sfc_step *step = (padt_sfc_step *)p;
    step->X = 1;
    step->T = 0;
    step->since = PADT_NO_TIME;
}

static inline int64_t
padt_elapsed(int on, int64_t *since, int64_t now)
{
    if (!on) {
        *since = PADT_NO_TIME;
        return -1;
    }
    if (*since == PADT_NO_TIME)
        *since = now;
    return now - *since;
}

static inline void
padt_action_update(char *p, int64_t now, int N, int R, int S, int P, int P0, int P1, int L,
                   int D, int SD, int DS, int SL, int64_t TL, int64_t TD, int64_t TSD,
                   int64_t TDS, int64_t TSL)
{
    padt_action_control *a = (padt_action_control *)p;
    a->stored = !R && (S || a->stored);
    int64_t l_elapsed = padt_elapsed(L, &a->l_since, now);
    int64_t d_elapsed = padt_elapsed(D, &a->d_since, now);
    a->sd_set = !R && (SD || a->sd_set);
    int64_t sd_elapsed = padt_elapsed(a->sd_set, &a->sd_since, now);
    int64_t ds_elapsed = padt_elapsed(DS, &a->ds_since, now);
    a->ds_stored = !R && ((ds_elapsed >= TDS && TDS >= 0 && DS) || a->ds_stored);
    a->sl_set = !R && (SL || a->sl_set);
    int64_t sl_elapsed = padt_elapsed(a->sl_set, &a->sl_since, now);
    int pulse = (P && !a->p_prev) || (P1 && !a->p1_prev) || (a->p0_prev && !P0);
    a->p_prev = P != 0;
    a->p1_prev = P1 != 0;
    a->p0_prev = P0 != 0;
    int active = !R && (N || (L && l_elapsed < TL) || (D && d_elapsed >= TD) || a->stored
                        || (a->sd_set && sd_elapsed >= TSD) || a->ds_stored
                        || (a->sl_set && sl_elapsed < TSL));
    int final_scan = a->held && !active;
    a->held = active != 0;
    a->Q = active || pulse;
    a->A = active || pulse || final_scan;
}

/* An array's element out of its bounds: the fault a Python list gives. */
static int
padt_index_error(void)
{
    PyErr_SetString(PyExc_IndexError, "list index out of range");
    return -1;
}

/* ---- structures outside the image: a FUNCTION's own (function_body.py) ---------------
 *
 * A FUNCTION of structures works in native memory on bytes of its frame (a parameter's
 * copy, a local, a result the caller's frame holds), laid out as the image's structures. */

/* The structure at `at` given to Python code: a view of the image where it lies there,
 * else of a copy of its bytes (a frame's: the callee gets a value of its own, as every
 * input and a FUNCTION's in-out are). A new reference. */
static PyObject *
padt_instance_object(padt_mctx *ctx, PyObject *view_class, char *at, Py_ssize_t size)
{
    if (at >= ctx->base && at + size <= ctx->base + ctx->size)
        return padt_view_new(view_class, ctx->image, at - ctx->base);
    PyObject *copy = PyByteArray_FromStringAndSize(at, size);
    if (copy == NULL)
        return NULL;
    PyObject *view = padt_view_new(view_class, copy, 0);
    Py_DECREF(copy);
    return view;
}

/* A structure Python code gave (a view of its class, or an object of the generated class
 * of the same name) into the `size` bytes at `at`: through a view of a scratch copy, as a
 * store of a whole structure takes it (padt_memory's `__padt_pack__`: every member checked),
 * then copied whole, so that a value refused leaves the bytes as they were. */
static int
padt_instance_into(PyObject *view_class, char *at, Py_ssize_t size, PyObject *value)
{
    if (Py_TYPE(value) == (PyTypeObject *)view_class) {
        padt_view *v = (padt_view *)value;
        memmove(at, PyByteArray_AS_STRING(v->image) + v->offset, size);
        return 0;
    }
    PyObject *scratch = PyByteArray_FromStringAndSize(at, size);
    PyObject *view = scratch == NULL ? NULL : padt_view_new(view_class, scratch, 0);
    PyObject *done = view == NULL ? NULL : PyObject_CallMethod(view, "__padt_pack__", "O", value);
    if (done != NULL)
        memcpy(at, PyByteArray_AS_STRING(scratch), size);
    Py_XDECREF(done);
    Py_XDECREF(view);
    Py_XDECREF(scratch);
    return done == NULL ? -1 : 0;
}

/* The bytes of a structure made afresh (`STRUCT_X()`: its members' initial values), made
 * once as the module binds: the generated class's object, into `at` as a store takes it. */
static int
padt_instance_initial(PyObject *view_class, const char *class_name, char *at, Py_ssize_t size)
{
    PyObject *cls = padt_class(class_name);
    PyObject *fresh = cls == NULL ? NULL : PyObject_CallNoArgs(cls);
    if (fresh == NULL)
        return -1;
    memset(at, 0, size);
    int failed = padt_instance_into(view_class, at, size, fresh);
    Py_DECREF(fresh);
    return failed;
}

/* A block's in-out whose offset lies outside the image (what padt_memory's views refuse
 * too: only a defect would write one). */
static int
padt_unbound_error(void)
{
    PyErr_SetString(PyExc_ReferenceError, "an in-out bound to no variable of the image");
    return -1;
}

/* The body as the `__call__` of its view class (a method descriptor of that class). */
static int
padt_add_view_method(PyObject *bodies, const char *class_name, PyMethodDef *def)
{
    PyObject *view_class = PyDict_GetItemString(padt_views, class_name);
    if (view_class == NULL || !PyType_Check(view_class)) {
        PyErr_Format(PyExc_TypeError, "native code: no view class %s", class_name);
        return -1;
    }
    return padt_add_method_of(bodies, class_name, def, (PyTypeObject *)view_class);
}

#endif /* PADT_NATIVE_H */

/* What the views of a memory image (padt_memory.c) and the C bodies that work on it
 * (padt_native.h, translate.py's memory mode) share: a view's object, and how a string
 * variable's bytes become a str and back (runtime/contract/layout.py: a uint16_t length
 * and the characters, of one byte for a STRING, two for a WSTRING).
 */
#ifndef PADT_IMAGE_H
#define PADT_IMAGE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* An instance in an image: the image (a bytearray whose size never changes) and where the
 * instance's bytes begin. */
typedef struct {
    PyObject_HEAD
    PyObject *image;
    Py_ssize_t offset;
} padt_view;

/* A view of class `type` (a subclass of padt_memory.View) of the instance at `offset` of
 * `image` (a new reference; the offset is the caller's to have checked). */
static inline PyObject *
padt_view_new(PyObject *type, PyObject *image, Py_ssize_t offset)
{
    PyTypeObject *kind = (PyTypeObject *)type;
    padt_view *view = (padt_view *)kind->tp_alloc(kind, 0);
    if (view == NULL)
        return NULL;
    view->image = Py_NewRef(image);
    view->offset = offset;
    return (PyObject *)view;
}

/* The value of an elementary variable of a layout's type code (runtime/contract/layout.py)
 * at `p`, as the contract represents it (a new reference; None for an "o" time that is
 * none), or NULL with SystemError for a code of no elementary type. */
static inline PyObject *
padt_scalar_get(int code, const char *p)
{
    switch (code) {
    case '?': return PyBool_FromLong(*(const uint8_t *)p != 0);
    case 'b': return PyLong_FromLong(*(const int8_t *)p);
    case 'B': return PyLong_FromLong(*(const uint8_t *)p);
    case 'h': { int16_t v; memcpy(&v, p, 2); return PyLong_FromLong(v); }
    case 'H': { uint16_t v; memcpy(&v, p, 2); return PyLong_FromLong(v); }
    case 'i': { int32_t v; memcpy(&v, p, 4); return PyLong_FromLong(v); }
    case 'I': { uint32_t v; memcpy(&v, p, 4); return PyLong_FromUnsignedLong(v); }
    case 'q': { int64_t v; memcpy(&v, p, 8); return PyLong_FromLongLong(v); }
    case 'Q': { uint64_t v; memcpy(&v, p, 8); return PyLong_FromUnsignedLongLong(v); }
    case 'f': { float v; memcpy(&v, p, 4); return PyFloat_FromDouble(v); }
    case 'd': { double v; memcpy(&v, p, 8); return PyFloat_FromDouble(v); }
    case 'o': {
        int64_t v;
        memcpy(&v, p, 8);
        if (v == INT64_MIN)
            Py_RETURN_NONE;
        return PyLong_FromLongLong(v);
    }
    }
    PyErr_Format(PyExc_SystemError, "padt: no elementary type of code %d", code);
    return NULL;
}

/* A TypeError: a variable of `what` cannot hold `value`; -1. */
static inline int
padt_refuse(const char *what, PyObject *value)
{
    PyErr_Format(PyExc_TypeError, "a variable of %s cannot hold %R", what, value);
    return -1;
}

/* an exact int within [low, high] (bool is no integer here: the slot holds an int) */
static inline int
padt_integer(PyObject *value, long long low, long long high, long long *out)
{
    if (!PyLong_CheckExact(value)) return padt_refuse("an integer type", value);
    int overflow = 0;
    long long v = PyLong_AsLongLongAndOverflow(value, &overflow);
    if (v == -1 && PyErr_Occurred()) return -1;
    if (overflow || v < low || v > high) {
        PyErr_Format(PyExc_OverflowError, "%R is outside the range of the variable", value);
        return -1;
    }
    *out = v;
    return 0;
}

/* `value` into an elementary variable of a layout's type code at `p`, checked as the
 * checked writers check it (its Python type, its range, a REAL rounded to 32 bits); -1
 * with the error, and the bytes as they were, for a value the variable cannot hold. */
static inline int
padt_scalar_set(int code, char *p, PyObject *value)
{
    long long v;
    switch (code) {
    case '?':
        if (!PyBool_Check(value)) return padt_refuse("BOOL", value);
        *(uint8_t *)p = value == Py_True;
        return 0;
    case 'b':
        if (padt_integer(value, INT8_MIN, INT8_MAX, &v)) return -1;
        *(int8_t *)p = (int8_t)v; return 0;
    case 'B':
        if (padt_integer(value, 0, UINT8_MAX, &v)) return -1;
        *(uint8_t *)p = (uint8_t)v; return 0;
    case 'h': { if (padt_integer(value, INT16_MIN, INT16_MAX, &v)) return -1;
        int16_t w = (int16_t)v; memcpy(p, &w, 2); return 0; }
    case 'H': { if (padt_integer(value, 0, UINT16_MAX, &v)) return -1;
        uint16_t w = (uint16_t)v; memcpy(p, &w, 2); return 0; }
    case 'i': { if (padt_integer(value, INT32_MIN, INT32_MAX, &v)) return -1;
        int32_t w = (int32_t)v; memcpy(p, &w, 4); return 0; }
    case 'I': { if (padt_integer(value, 0, UINT32_MAX, &v)) return -1;
        uint32_t w = (uint32_t)v; memcpy(p, &w, 4); return 0; }
    case 'q': { if (padt_integer(value, INT64_MIN, INT64_MAX, &v)) return -1;
        int64_t w = (int64_t)v; memcpy(p, &w, 8); return 0; }
    case 'o': {
        int64_t w = INT64_MIN;
        if (value != Py_None) {
            if (padt_integer(value, INT64_MIN + 1, INT64_MAX, &v)) return -1;
            w = (int64_t)v;
        }
        memcpy(p, &w, 8);
        return 0;
    }
    case 'Q': {
        if (!PyLong_CheckExact(value)) return padt_refuse("an integer type", value);
        unsigned long long u = PyLong_AsUnsignedLongLong(value);
        if (u == (unsigned long long)-1 && PyErr_Occurred()) {
            PyErr_Format(PyExc_OverflowError, "%R is outside the range of the variable", value);
            return -1;
        }
        uint64_t w = (uint64_t)u; memcpy(p, &w, 8); return 0;
    }
    case 'f': case 'd': {
        if (!PyFloat_CheckExact(value)) return padt_refuse("REAL or LREAL", value);
        double d = PyFloat_AS_DOUBLE(value);
        if (code == 'd') { memcpy(p, &d, 8); return 0; }
        float s = (float)d;
        if ((double)s != d && !(d != d)) /* the slot holds REALs rounded to 32 bits */
            return padt_refuse("REAL (a value rounded to 32 bits)", value);
        memcpy(p, &s, 4);
        return 0;
    }
    }
    PyErr_Format(PyExc_SystemError, "padt: no elementary type of code %d", code);
    return -1;
}

/* The str a string variable holds (a new reference); a length beyond the most the
 * variable holds, which no writer stores, is read as that most. */
static inline PyObject *
padt_chars_get(const char *p, Py_ssize_t most, int wide)
{
    uint16_t n;
    memcpy(&n, p, 2);
    if (n > most)
        n = (uint16_t)most;
    /* the characters follow the length at an even offset: aligned for Py_UCS2 */
    return PyUnicode_FromKindAndData(wide ? PyUnicode_2BYTE_KIND : PyUnicode_1BYTE_KIND, p + 2, n);
}

/* `text` into a string variable of at most `most` characters; -1 with ValueError (and the
 * variable as it was) for a longer one or a character beyond one byte (two, `wide`). */
static inline int
padt_chars_set(char *p, Py_ssize_t most, int wide, PyObject *text)
{
    if (!PyUnicode_Check(text)) {
        PyErr_Format(PyExc_TypeError, "a variable of STRING or WSTRING cannot hold %R", text);
        return -1;
    }
    Py_ssize_t n = PyUnicode_GET_LENGTH(text);
    if (n > most) {
        PyErr_Format(PyExc_ValueError, "%R is longer than the variable's %zd characters", text,
                     most);
        return -1;
    }
    int kind = PyUnicode_KIND(text);
    const void *data = PyUnicode_DATA(text);
    if (kind != PyUnicode_1BYTE_KIND) {
        Py_UCS4 limit = wide ? 0xFFFF : 0xFF;
        for (Py_ssize_t i = 0; i < n; i++) {
            if (PyUnicode_READ(kind, data, i) > limit) {
                PyErr_Format(PyExc_ValueError, "%R has a character beyond %s", text,
                             wide ? "two bytes" : "one byte");
                return -1;
            }
        }
    }
    for (Py_ssize_t i = 0; i < n; i++) {
        Py_UCS4 c = PyUnicode_READ(kind, data, i);
        if (wide) {
            uint16_t unit = (uint16_t)c;
            memcpy(p + 2 + 2 * i, &unit, 2);
        } else {
            ((uint8_t *)p)[2 + i] = (uint8_t)c;
        }
    }
    uint16_t length = (uint16_t)n;
    memcpy(p, &length, 2);
    return 0;
}

/* The head of an array's shape (padt_list_of's grammar): its count and stride, and
 * where its element's begins; -1 with SystemError for a shape that cannot be read. */
static inline int
padt_array_head(const char *shape, long *count, long *stride, const char **element)
{
    char *end;
    *count = strtol(shape, &end, 10);
    *stride = *end == 'x' ? strtol(end + 1, &end, 10) : -1;
    if (*count < 1 || *stride < 0 || *end != ':') {
        PyErr_SetString(PyExc_SystemError, "padt: an array's shape that cannot be read");
        return -1;
    }
    *element = end + 1;
    return 0;
}

/* A new list of the array at `at`, as `_copy` hands an array to Python code (an input or
 * an in-out of a FUNCTION or a method): `*shape` says what it holds, and is left past
 * what was read of it. Made by runtime/code/native/image_body.py (`list_shape`):
 *   array   := count "x" stride ":" element
 *   element := a type code of padt_scalar_get | ("s" | "w") most ";" | "[" array "]" */
static inline PyObject *
padt_list_of(const char *at, const char **shape)
{
    char *end;
    long count, stride;
    const char *element;
    if (padt_array_head(*shape, &count, &stride, &element) < 0)
        return NULL;
    const char *after = element;
    PyObject *list = PyList_New(count);
    for (long i = 0; list != NULL && i < count; i++) {
        const char *p = at + i * stride, *s = element;
        PyObject *item;
        if (*s == '[') {
            s++;
            item = padt_list_of(p, &s);
            if (item != NULL && *s++ != ']') {
                Py_CLEAR(item);
                PyErr_SetString(PyExc_SystemError, "padt: an array's shape without its ]");
            }
        } else if (*s == 's' || *s == 'w') {
            long most = strtol(s + 1, &end, 10);
            item = padt_chars_get(p, most, *s == 'w');
            s = end + 1; /* past the ";" */
        } else {
            item = padt_scalar_get(*s++, p);
        }
        if (item == NULL) {
            Py_CLEAR(list);
            break;
        }
        PyList_SET_ITEM(list, i, item);
        after = s;
    }
    *shape = after;
    return list;
}

/* The values of `list` into the array at `at` that `*shape` describes (padt_list_of's),
 * each checked as a store is; `*shape` left past what was read of it. 0, or -1 with the
 * error (part of the array written: padt_list_into writes into a copy). */
static inline int
padt_list_write(char *at, const char **shape, PyObject *list)
{
    char *end;
    long count, stride;
    const char *element;
    if (padt_array_head(*shape, &count, &stride, &element) < 0)
        return -1;
    PyObject *items = PySequence_Fast(list, "an array takes a sequence");
    if (items == NULL)
        return -1;
    int failed = 0;
    if (PySequence_Fast_GET_SIZE(items) != count) {
        PyErr_Format(PyExc_ValueError, "an array of %ld elements cannot take %zd", count,
                     PySequence_Fast_GET_SIZE(items));
        failed = -1;
    }
    const char *after = element;
    for (long i = 0; !failed && i < count; i++) {
        char *p = at + i * stride;
        const char *s = element;
        PyObject *item = PySequence_Fast_GET_ITEM(items, i);
        if (*s == '[') {
            s++;
            failed = padt_list_write(p, &s, item);
            if (!failed && *s++ != ']') {
                PyErr_SetString(PyExc_SystemError, "padt: an array's shape without its ]");
                failed = -1;
            }
        } else if (*s == 's' || *s == 'w') {
            long most = strtol(s + 1, &end, 10);
            failed = padt_chars_set(p, most, *s == 'w', item);
            s = end + 1;
        } else {
            failed = padt_scalar_set(*s++, p, item);
        }
        after = s;
    }
    Py_DECREF(items);
    *shape = after;
    return failed ? -1 : 0;
}

/* `list` (what Python code gave back for an array: an in-out of a FUNCTION or a method)
 * into the array at `at` of `shape`, written into a copy first: a value refused leaves
 * the array as it was. */
static inline int
padt_list_into(char *at, const char *shape, PyObject *list)
{
    long count, stride;
    const char *element;
    if (padt_array_head(shape, &count, &stride, &element) < 0)
        return -1;
    size_t size = (size_t)count * (size_t)stride;
    char *scratch = PyMem_Malloc(size ? size : 1);
    if (scratch == NULL) {
        PyErr_NoMemory();
        return -1;
    }
    memcpy(scratch, at, size);
    const char *s = shape;
    int failed = padt_list_write(scratch, &s, list);
    if (!failed)
        memcpy(at, scratch, size);
    PyMem_Free(scratch);
    return failed;
}

/* padt_list_of, from the whole of a shape. */
static inline PyObject *
padt_list_from(const char *at, const char *shape)
{
    return padt_list_of(at, &shape);
}

#endif /* PADT_IMAGE_H */

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

/* A new list of the array at `at`, as `_copy` hands an array to Python code (an input or
 * an in-out of a FUNCTION or a method): `*shape` says what it holds, and is left past
 * what was read of it. Made by runtime/code/native/image_body.py (`list_shape`):
 *   array   := count "x" stride ":" element
 *   element := a type code of padt_scalar_get | ("s" | "w") most ";" | "[" array "]" */
static inline PyObject *
padt_list_of(const char *at, const char **shape)
{
    char *end;
    long count = strtol(*shape, &end, 10);
    long stride = *end == 'x' ? strtol(end + 1, &end, 10) : -1;
    if (count < 1 || stride < 0 || *end != ':') {
        PyErr_SetString(PyExc_SystemError, "padt: an array's shape that cannot be read");
        return NULL;
    }
    const char *element = end + 1, *after = element;
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

/* padt_list_of, from the whole of a shape. */
static inline PyObject *
padt_list_from(const char *at, const char *shape)
{
    return padt_list_of(at, &shape);
}

#endif /* PADT_IMAGE_H */

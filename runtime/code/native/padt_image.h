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

#endif /* PADT_IMAGE_H */

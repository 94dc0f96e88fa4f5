/* Views of a configuration's memory image (docs/native-code.md, "Variables in native
 * memory"): Python objects that read and write the image's bytes where generated Python
 * code, the debugger and the services read and write the attributes of slot objects.
 *
 * A view is (image, offset): the image a bytearray that never changes its size, the
 * offset where the instance's struct begins. Its class is made per generated class
 * (image_views.py): a subclass of View whose attributes are Field descriptors, one per
 * member, each knowing the member's type code, offset and size. An array reads as an
 * Elements view (length, index, assignment; deepcopy gives a list). Every store checks the
 * value as the checked writers do (its type, its range, a string's length and characters),
 * so a view never holds what the slot object would refuse to be given.
 *
 * A block's in-out of an array or structure (layout.py's Bound) is the offset of the
 * variable a call bound it to, then storage of its own: it reads as a view of that
 * variable, and a store of a variable of the image binds it there (what the code's
 * `f.data = s.arr` before a call does); a store of anything else goes into its own storage.
 *
 * Included after `#define PADT_INIT PyInit_<module name>` (the module is named by the
 * hash of its source, as every module of the native tier).
 */
#include "padt_image.h"

typedef padt_view ViewObject;

/* What a Field reads and writes. */
enum {
    K_BOOL = '?', K_I8 = 'b', K_U8 = 'B', K_I16 = 'h', K_U16 = 'H', K_I32 = 'i',
    K_U32 = 'I', K_I64 = 'q', K_U64 = 'Q', K_F32 = 'f', K_F64 = 'd',
    K_SINCE = 'o',  /* an int64_t that is None at INT64_MIN (the runtime's step times) */
    K_CHARS = 's', K_WCHARS = 'w', /* a length and `length` + 1 characters */
    K_NESTED = 'n', /* a struct: a view of `view_type` */
    K_ARRAY = 'a',  /* `count` elements of `element`, `stride` bytes apart */
    K_BOUND = 'r',  /* an in-out: the uint32_t offset of an `element`, one of its own at `own` */
};

typedef struct FieldObject {
    PyObject_HEAD
    int code;
    Py_ssize_t offset; /* in the struct that holds it */
    Py_ssize_t size;   /* bytes */
    Py_ssize_t length; /* K_CHARS, K_WCHARS: the most characters */
    PyObject *view_type; /* K_NESTED */
    struct FieldObject *element; /* K_ARRAY: the element at offset 0; K_BOUND: the target */
    Py_ssize_t count, stride;    /* K_ARRAY */
    Py_ssize_t own;              /* K_BOUND: where its own target begins, from its start */
} FieldObject;

typedef struct {
    PyObject_HEAD
    PyObject *image;
    Py_ssize_t offset;
    FieldObject *element;
    Py_ssize_t count, stride;
} ElementsObject;

static PyTypeObject ViewType;
static PyTypeObject FieldType;
static PyTypeObject ElementsType;

static char *at(PyObject *image, Py_ssize_t offset) {
    return PyByteArray_AS_STRING(image) + offset;
}

#define view_at padt_view_new

/* A Field the cycle collector cleared (its class being freed) reads and writes nothing. */
static int field_cleared(FieldObject *f) {
    if ((f->code == K_NESTED && f->view_type == NULL) ||
        ((f->code == K_ARRAY || f->code == K_BOUND) && f->element == NULL)) {
        PyErr_SetString(PyExc_ReferenceError, "a member of a view class being freed");
        return 1;
    }
    return 0;
}

/* Where the in-out at `offset` is bound: the offset of its target, checked to lie in the
 * image (only the views, pack and the C bodies write it, each an offset they found there;
 * the check keeps a defect from reading beyond the image); -1 with an error. */
static Py_ssize_t bound_target(FieldObject *f, PyObject *image, Py_ssize_t offset) {
    uint32_t target;
    memcpy(&target, at(image, offset), sizeof target);
    if (target == 0 || (Py_ssize_t)target + f->element->size > PyByteArray_GET_SIZE(image)) {
        PyErr_SetString(PyExc_ReferenceError, "an in-out bound to no variable of the image");
        return -1;
    }
    return target;
}

static void bind_at(PyObject *image, Py_ssize_t offset, Py_ssize_t target) {
    uint32_t where = (uint32_t)target;
    memcpy(at(image, offset), &where, sizeof where);
}

/* Whether two fields read and write the same type (an in-out takes a variable of its own
 * type only). */
static int same_type(FieldObject *a, FieldObject *b) {
    if (a == b) return 1;
    if (a == NULL || b == NULL || a->code != b->code || a->size != b->size ||
        a->length != b->length || a->count != b->count || a->stride != b->stride ||
        a->view_type != b->view_type)
        return 0;
    return a->element == NULL ? b->element == NULL : same_type(a->element, b->element);
}

static PyObject *read_field(FieldObject *f, PyObject *image, Py_ssize_t offset) {
    if (field_cleared(f)) return NULL;
    char *p = at(image, offset);
    switch (f->code) {
    case K_BOOL: case K_I8: case K_U8: case K_I16: case K_U16: case K_I32: case K_U32:
    case K_I64: case K_U64: case K_F32: case K_F64: case K_SINCE:
        return padt_scalar_get(f->code, p);
    case K_CHARS: case K_WCHARS: return padt_chars_get(p, f->length, f->code == K_WCHARS);
    case K_NESTED: return view_at(f->view_type, image, offset);
    case K_ARRAY: {
        ElementsObject *e = PyObject_New(ElementsObject, &ElementsType);
        if (e == NULL) return NULL;
        Py_INCREF(image);
        Py_INCREF(f->element);
        e->image = image;
        e->offset = offset;
        e->element = f->element;
        e->count = f->count;
        e->stride = f->stride;
        return (PyObject *)e;
    }
    case K_BOUND: {
        Py_ssize_t target = bound_target(f, image, offset);
        return target < 0 ? NULL : read_field(f->element, image, target);
    }
    }
    PyErr_SetString(PyExc_SystemError, "padt_memory: a field of no known kind");
    return NULL;
}

static PyObject *members_of(PyObject *view_type);
typedef struct moving moving;
static int pack_members(PyObject *members, PyObject *image, Py_ssize_t offset, PyObject *source,
                        moving *mv);

/* A whole structure or instance, of `size` bytes at `offset`, from an object of the class
 * `view_type` stands for (of the same name: a structure a FUNCTION's Python made), packed as
 * the tier switch packs a slot object, into a copy first, so that a member refused leaves
 * the bytes as they were. */
static int write_members(PyObject *view_type, Py_ssize_t size, PyObject *image,
                         Py_ssize_t offset, PyObject *value) {
    const char *name = ((PyTypeObject *)view_type)->tp_name;
    if (PyObject_TypeCheck(value, &ViewType) || strcmp(Py_TYPE(value)->tp_name, name) != 0)
        return padt_refuse(name, value);
    PyObject *members = members_of(view_type);
    if (members == NULL) return -1;
    PyObject *scratch = PyByteArray_FromStringAndSize(at(image, offset), size);
    int failed = scratch == NULL || pack_members(members, scratch, 0, value, NULL) < 0;
    if (!failed) memcpy(at(image, offset), PyByteArray_AS_STRING(scratch), size);
    Py_XDECREF(scratch);
    Py_DECREF(members);
    return failed ? -1 : 0;
}

static int write_field(FieldObject *f, PyObject *image, Py_ssize_t offset, PyObject *value);

/* An in-out bound: to a variable of the image of its type (a view, an array's Elements),
 * or else `value` written into its own storage, to which it is bound. */
static int bind_field(FieldObject *f, PyObject *image, Py_ssize_t offset, PyObject *value) {
    FieldObject *target = f->element;
    if (target->code == K_NESTED && Py_TYPE(value) == (PyTypeObject *)target->view_type &&
        ((ViewObject *)value)->image == image) {
        bind_at(image, offset, ((ViewObject *)value)->offset);
        return 0;
    }
    if (target->code == K_ARRAY && Py_IS_TYPE(value, &ElementsType)) {
        ElementsObject *e = (ElementsObject *)value;
        if (e->image == image && e->count == target->count && e->stride == target->stride &&
            same_type(e->element, target->element)) {
            bind_at(image, offset, e->offset);
            return 0;
        }
    }
    if (write_field(target, image, offset + f->own, value) < 0) return -1;
    bind_at(image, offset, offset + f->own);
    return 0;
}

static int write_field(FieldObject *f, PyObject *image, Py_ssize_t offset, PyObject *value) {
    if (field_cleared(f)) return -1;
    char *p = at(image, offset);
    switch (f->code) {
    case K_BOOL: case K_I8: case K_U8: case K_I16: case K_U16: case K_I32: case K_U32:
    case K_I64: case K_U64: case K_F32: case K_F64: case K_SINCE:
        return padt_scalar_set(f->code, p, value);
    case K_CHARS: case K_WCHARS: return padt_chars_set(p, f->length, f->code == K_WCHARS, value);
    case K_NESTED:
        /* a whole structure or instance: from a view of the same class (a copy), or from
           an object of its class */
        if (Py_TYPE(value) != (PyTypeObject *)f->view_type)
            return write_members(f->view_type, f->size, image, offset, value);
        memmove(p, at(((ViewObject *)value)->image, ((ViewObject *)value)->offset), f->size);
        return 0;
    case K_ARRAY: {
        /* a whole array: from a sequence of as many elements (a list, another view),
           written into a copy first, so an element refused leaves the array as it was */
        PyObject *items = PySequence_Fast(value, "an array takes a sequence");
        if (items == NULL) return -1;
        if (PySequence_Fast_GET_SIZE(items) != f->count) {
            PyErr_Format(PyExc_ValueError, "an array of %zd elements cannot take %zd",
                         f->count, PySequence_Fast_GET_SIZE(items));
            Py_DECREF(items);
            return -1;
        }
        PyObject *scratch = PyByteArray_FromStringAndSize(p, f->size);
        if (scratch == NULL) {
            Py_DECREF(items);
            return -1;
        }
        int failed = 0;
        for (Py_ssize_t i = 0; i < f->count && !failed; i++) {
            PyObject *item = PySequence_Fast_GET_ITEM(items, i);
            failed = write_field(f->element, scratch, i * f->stride, item);
        }
        if (!failed) memcpy(at(image, offset), PyByteArray_AS_STRING(scratch), f->size);
        Py_DECREF(scratch);
        Py_DECREF(items);
        return failed ? -1 : 0;
    }
    case K_BOUND: return bind_field(f, image, offset, value);
    }
    PyErr_SetString(PyExc_SystemError, "padt_memory: a field of no known kind");
    return -1;
}

/* ---- Field: the descriptor of one member ---- */

static PyObject *field_get(PyObject *self, PyObject *obj, PyObject *type) {
    if (obj == NULL || obj == Py_None) {
        Py_INCREF(self);
        return self;
    }
    if (!PyObject_TypeCheck(obj, &ViewType)) return PyErr_Format(PyExc_TypeError, "not a view");
    ViewObject *view = (ViewObject *)obj;
    FieldObject *f = (FieldObject *)self;
    return read_field(f, view->image, view->offset + f->offset);
}

static int field_set(PyObject *self, PyObject *obj, PyObject *value) {
    if (value == NULL) {
        PyErr_SetString(PyExc_AttributeError, "a variable of the image cannot be deleted");
        return -1;
    }
    if (!PyObject_TypeCheck(obj, &ViewType)) {
        PyErr_SetString(PyExc_TypeError, "not a view");
        return -1;
    }
    ViewObject *view = (ViewObject *)obj;
    FieldObject *f = (FieldObject *)self;
    return write_field(f, view->image, view->offset + f->offset, value);
}

static PyObject *field_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    static char *names[] = {"code", "offset", "size", "length", "view_type", "element",
                            "count", "stride", "own", NULL};
    int code;
    Py_ssize_t offset, size, length = 0, count = 0, stride = 0, own = 0;
    PyObject *view_type = Py_None, *element = Py_None;
    if (!PyArg_ParseTupleAndKeywords(args, kwds, "Cnn|nOOnnn", names, &code, &offset, &size,
                                     &length, &view_type, &element, &count, &stride, &own))
        return NULL;
    if (code == K_NESTED && !(PyType_Check(view_type) &&
                              PyType_IsSubtype((PyTypeObject *)view_type, &ViewType)))
        return PyErr_Format(PyExc_TypeError, "a nested field needs a view type");
    if ((code == K_ARRAY || code == K_BOUND) && !PyObject_TypeCheck(element, &FieldType))
        return PyErr_Format(PyExc_TypeError, "an array or in-out field needs an element field");
    if (code == K_BOUND &&
        (((FieldObject *)element)->code != K_NESTED && ((FieldObject *)element)->code != K_ARRAY))
        return PyErr_Format(PyExc_TypeError, "an in-out field of an array or structure only");
    if (offset < 0 || size < 0 || length < 0 || length > UINT16_MAX || count < 0 || stride < 0 ||
        own < 0 || (code == K_BOUND && (own < 4 || own + ((FieldObject *)element)->size > size)))
        return PyErr_Format(PyExc_ValueError, "a field's sizes are no sizes");
    FieldObject *f = (FieldObject *)type->tp_alloc(type, 0);
    if (f == NULL) return NULL;
    f->code = code;
    f->offset = offset;
    f->size = size;
    f->length = length;
    f->count = count;
    f->stride = stride;
    f->own = own;
    f->view_type = code == K_NESTED ? Py_NewRef(view_type) : NULL;
    f->element = code == K_ARRAY || code == K_BOUND ? (FieldObject *)Py_NewRef(element) : NULL;
    return (PyObject *)f;
}

/* A Field is seen by the cycle collector: a view class's dict holds its Fields, a nested
 * Field holds another view class, and the classes of a configuration reach each other
 * through their generated code's namespace. Unseen, that edge would keep every class of a
 * configuration (and the C modules bound to them) alive after a cold start. */
static int field_traverse(PyObject *self, visitproc visit, void *arg) {
    FieldObject *f = (FieldObject *)self;
    Py_VISIT(f->view_type);
    Py_VISIT(f->element);
    return 0;
}

static int field_clear(PyObject *self) {
    FieldObject *f = (FieldObject *)self;
    Py_CLEAR(f->view_type);
    Py_CLEAR(f->element);
    return 0;
}

static void field_dealloc(PyObject *self) {
    PyObject_GC_UnTrack(self);
    field_clear(self);
    Py_TYPE(self)->tp_free(self);
}

static PyTypeObject FieldType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "padt_memory.Field",
    .tp_basicsize = sizeof(FieldObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_traverse = field_traverse,
    .tp_clear = field_clear,
    .tp_doc = "One member of a view's class: its type code, offset and size.",
    .tp_new = field_new,
    .tp_dealloc = field_dealloc,
    .tp_descr_get = field_get,
    .tp_descr_set = field_set,
};

/* ---- View: an instance in the image ---- */

static PyObject *view_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    PyObject *image;
    Py_ssize_t offset;
    if (!PyArg_ParseTuple(args, "O!n", &PyByteArray_Type, &image, &offset)) return NULL;
    PyObject *size = PyObject_GetAttrString((PyObject *)type, "__size__");
    if (size == NULL) return NULL;
    Py_ssize_t bytes = PyLong_AsSsize_t(size);
    Py_DECREF(size);
    if (bytes == -1 && PyErr_Occurred()) return NULL;
    if (offset < 0 || offset + bytes > PyByteArray_GET_SIZE(image))
        return PyErr_Format(PyExc_ValueError, "a view beyond its image");
    return view_at((PyObject *)type, image, offset);
}

static void view_dealloc(PyObject *self) {
    Py_XDECREF(((ViewObject *)self)->image);
    Py_TYPE(self)->tp_free(self);
}

static PyObject *view_deepcopy(PyObject *self, PyObject *memo) {
    /* a copy of the instance's bytes, detached from the image (what `_copy` makes of a
       structure to assign it whole) */
    ViewObject *view = (ViewObject *)self;
    PyObject *size = PyObject_GetAttrString((PyObject *)Py_TYPE(self), "__size__");
    if (size == NULL) return NULL;
    Py_ssize_t bytes = PyLong_AsSsize_t(size);
    Py_DECREF(size);
    if (bytes == -1 && PyErr_Occurred()) return NULL;
    PyObject *copy = PyByteArray_FromStringAndSize(at(view->image, view->offset), bytes);
    if (copy == NULL) return NULL;
    PyObject *detached = view_at((PyObject *)Py_TYPE(self), copy, 0);
    Py_DECREF(copy);
    return detached;
}

/* `__padt_pack__(object)`: an object of the view's class (of the same name, a slot object)
 * into the view's bytes, as a store of a whole structure takes it (write_members): what a
 * FUNCTION's C in native memory makes of a structure its Python gave (padt_native.h). */
static PyObject *view_pack(PyObject *self, PyObject *value) {
    PyObject *size = PyObject_GetAttrString((PyObject *)Py_TYPE(self), "__size__");
    if (size == NULL) return NULL;
    Py_ssize_t bytes = PyLong_AsSsize_t(size);
    Py_DECREF(size);
    if (bytes == -1 && PyErr_Occurred()) return NULL;
    ViewObject *view = (ViewObject *)self;
    if (write_members((PyObject *)Py_TYPE(self), bytes, view->image, view->offset, value) < 0)
        return NULL;
    Py_RETURN_NONE;
}

static PyObject *view_where(PyObject *self, PyObject *unused) {
    ViewObject *view = (ViewObject *)self;
    return Py_BuildValue("(On)", view->image, view->offset);
}

/* `copy_globals` between two views of one class (a program's own view of the globals and
   the globals): each named member's bytes at once, which is a copy by value (arrays and
   structures are inline), of values the target's own fields would store as they are. */
static PyObject *view_copy(PyObject *self, PyObject *args) {
    PyObject *target, *names;
    if (!PyArg_ParseTuple(args, "OO!", &target, &PyTuple_Type, &names)) return NULL;
    if (Py_TYPE(target) != Py_TYPE(self))
        return PyErr_Format(PyExc_TypeError, "a copy between views of two classes");
    ViewObject *from = (ViewObject *)self, *to = (ViewObject *)target;
    for (Py_ssize_t i = 0; i < PyTuple_GET_SIZE(names); i++) {
        PyObject *name = PyTuple_GET_ITEM(names, i);
        PyObject *found = PyUnicode_Check(name) ? _PyType_Lookup(Py_TYPE(self), name) : NULL;
        if (found == NULL || !PyObject_TypeCheck(found, &FieldType))
            return PyErr_Format(PyExc_AttributeError, "no member %R to copy", name);
        FieldObject *f = (FieldObject *)found;
        if (field_cleared(f)) return NULL;
        memmove(at(to->image, to->offset + f->offset), at(from->image, from->offset + f->offset),
                f->size);
    }
    Py_RETURN_NONE;
}

static PyMethodDef view_methods[] = {
    {"__deepcopy__", view_deepcopy, METH_O, "A copy detached from the image."},
    {"__padt_where__", view_where, METH_NOARGS, "(image, offset)"},
    {"__padt_pack__", view_pack, METH_O, "(object): a slot object of its class into its bytes."},
    {"__padt_copy__", view_copy, METH_VARARGS, "(target, names): members copied by value."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject ViewType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "padt_memory.View",
    .tp_basicsize = sizeof(ViewObject),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_BASETYPE,
    .tp_doc = "An instance in a memory image: (image, offset).",
    .tp_new = view_new,
    .tp_dealloc = view_dealloc,
    .tp_methods = view_methods,
};

/* ---- Elements: an array in the image ---- */

static Py_ssize_t elements_length(PyObject *self) { return ((ElementsObject *)self)->count; }

static int elements_index(ElementsObject *e, Py_ssize_t i) {
    if (i < 0 || i >= e->count) {
        PyErr_SetString(PyExc_IndexError, "list index out of range");
        return -1;
    }
    return 0;
}

static PyObject *elements_item(PyObject *self, Py_ssize_t i) {
    ElementsObject *e = (ElementsObject *)self;
    if (elements_index(e, i)) return NULL;
    return read_field(e->element, e->image, e->offset + i * e->stride);
}

static int elements_assign(PyObject *self, Py_ssize_t i, PyObject *value) {
    ElementsObject *e = (ElementsObject *)self;
    if (value == NULL) {
        PyErr_SetString(PyExc_TypeError, "an element of an array cannot be deleted");
        return -1;
    }
    if (elements_index(e, i)) return -1;
    return write_field(e->element, e->image, e->offset + i * e->stride, value);
}

static PyObject *elements_deepcopy(PyObject *self, PyObject *memo) {
    /* a list, as the Python tier holds an array: elements that are arrays or instances
       copied too */
    ElementsObject *e = (ElementsObject *)self;
    PyObject *list = PyList_New(e->count);
    if (list == NULL) return NULL;
    for (Py_ssize_t i = 0; i < e->count; i++) {
        PyObject *item = read_field(e->element, e->image, e->offset + i * e->stride);
        if (item != NULL && (e->element->code == K_ARRAY || e->element->code == K_NESTED)) {
            PyObject *copied = PyObject_CallMethod(item, "__deepcopy__", "O", memo);
            Py_DECREF(item);
            item = copied;
        }
        if (item == NULL) {
            Py_DECREF(list);
            return NULL;
        }
        PyList_SET_ITEM(list, i, item);
    }
    return list;
}

static void elements_dealloc(PyObject *self) {
    ElementsObject *e = (ElementsObject *)self;
    Py_XDECREF(e->image);
    Py_XDECREF(e->element);
    PyObject_Free(self);
}

static PyObject *elements_richcompare(PyObject *self, PyObject *other, int op) {
    /* equal to a list or another view of the same values, as lists compare */
    if (op != Py_EQ && op != Py_NE) Py_RETURN_NOTIMPLEMENTED;
    PyObject *mine = elements_deepcopy(self, Py_None);
    if (mine == NULL) return NULL;
    PyObject *theirs = PyObject_TypeCheck(other, &ElementsType)
                           ? elements_deepcopy(other, Py_None)
                           : Py_NewRef(other);
    if (theirs == NULL) {
        Py_DECREF(mine);
        return NULL;
    }
    PyObject *result = PyObject_RichCompare(mine, theirs, op);
    Py_DECREF(mine);
    Py_DECREF(theirs);
    return result;
}

static PySequenceMethods elements_sequence = {
    .sq_length = elements_length,
    .sq_item = elements_item,
    .sq_ass_item = elements_assign,
};

static PyMethodDef elements_methods[] = {
    {"__deepcopy__", elements_deepcopy, METH_O, "The values as a list."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject ElementsType = {
    PyVarObject_HEAD_INIT(NULL, 0)
    .tp_name = "padt_memory.Elements",
    .tp_basicsize = sizeof(ElementsObject),
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "An array in a memory image.",
    .tp_dealloc = elements_dealloc,
    .tp_as_sequence = &elements_sequence,
    .tp_methods = elements_methods,
    .tp_richcompare = elements_richcompare,
    .tp_hash = PyObject_HashNotImplemented,
};

/* ---- pack and unpack: a whole instance between slot objects and the image ----
 *
 * What the tier switch (runtime/image_switch.py) does with every instance of a
 * configuration, in C: 100,000 variables took about 40 ms each way as Python's
 * getattr and setattr per member, on the cycle thread. The members are the view class's
 * `__slots__`, each with its Field in the class's dict; a slot object of the generated
 * class has the same slots. */

/* [(name, Field)] of a view class's members: a new list. */
static PyObject *members_of(PyObject *view_type) {
    PyObject *names = PyObject_GetAttrString(view_type, "__slots__");
    if (names == NULL) return NULL;
    PyObject *seq = PySequence_Fast(names, "__slots__ is no sequence");
    Py_DECREF(names);
    if (seq == NULL) return NULL;
    Py_ssize_t n = PySequence_Fast_GET_SIZE(seq);
    PyObject *members = PyList_New(n);
    PyObject *dict = ((PyTypeObject *)view_type)->tp_dict;
    for (Py_ssize_t i = 0; members != NULL && i < n; i++) {
        PyObject *name = PySequence_Fast_GET_ITEM(seq, i);
        PyObject *field = PyDict_GetItemWithError(dict, name);
        if (field == NULL || !PyObject_TypeCheck(field, &FieldType)) {
            if (!PyErr_Occurred())
                PyErr_Format(PyExc_TypeError, "%R is no member of the view class", name);
            Py_CLEAR(members);
            break;
        }
        PyObject *pair = PyTuple_Pack(2, name, field);
        if (pair == NULL) {
            Py_CLEAR(members);
            break;
        }
        PyList_SET_ITEM(members, i, pair);
    }
    Py_DECREF(seq);
    return members;
}

/* An identity map kept across a whole configuration's pack or unpack: where each array and
 * structure went, and the in-outs to bind once all have gone. An in-out bound to a
 * variable of another instance (a global, another program's) is bound to it however the
 * instances are ordered. */
struct moving {
    PyObject *seen;    /* pack: id of an object -> (offset, Field); unpack: key -> object;
                          NULL where no class has an in-out (nothing to bind) */
    PyObject *pending; /* pack: (offset, Field, object); unpack: (offset, Field, holder, name) */
};

static int unpack_members(PyObject *members, PyObject *image, Py_ssize_t offset, PyObject *target,
                          moving *mv);

/* The members of a nested field's view class, or NULL with no error for any other field:
 * found once for all the elements of an array. */
static PyObject *nested_members(FieldObject *f, int *failed) {
    *failed = 0;
    if (f->code != K_NESTED) return NULL;
    PyObject *members = members_of(f->view_type);
    *failed = members == NULL;
    return members;
}

/* What unpack knows a place of the image by: its offset and what its type is made of (a
 * structure and its first member begin at one offset; two fields of one type are two
 * Field objects). */
static PyObject *place_key(FieldObject *f, Py_ssize_t offset) {
    FieldObject *e = f->element;
    PyObject *of = f->view_type ? f->view_type : (e && e->view_type ? e->view_type : Py_None);
    return Py_BuildValue("(ninnnOi)", offset, f->code, f->size, f->count, f->stride, of,
                         e ? e->code : 0);
}

static int remember(moving *mv, PyObject *key, PyObject *value) {
    if (key == NULL || value == NULL) {
        Py_XDECREF(key);
        Py_XDECREF(value);
        return -1;
    }
    int failed = PyDict_SetItem(mv->seen, key, value);
    Py_DECREF(key);
    Py_DECREF(value);
    return failed;
}

/* An array or structure object packed at `offset`, for the in-outs bound to it. */
static int packed_at(moving *mv, FieldObject *f, Py_ssize_t offset, PyObject *object) {
    return remember(mv, PyLong_FromVoidPtr(object), Py_BuildValue("(nO)", offset, f));
}

/* `value`, held by slot objects (an instance, a list), into the bytes at `offset`;
 * `members`: those of `f`'s class when it is nested, else NULL. `mv` NULL: an instance
 * with in-outs is refused (a structure given whole has none). */
static int pack_value(FieldObject *f, PyObject *members, PyObject *image, Py_ssize_t offset,
                      PyObject *value, moving *mv) {
    if (field_cleared(f)) return -1;
    if (f->code == K_BOUND) {
        if (mv == NULL) {
            PyErr_SetString(PyExc_TypeError, "an instance with in-outs given whole");
            return -1;
        }
        PyObject *entry = Py_BuildValue("(nOO)", offset, f, value);
        int failed = entry == NULL || PyList_Append(mv->pending, entry) < 0;
        Py_XDECREF(entry);
        return failed ? -1 : 0;
    }
    if ((f->code == K_NESTED || f->code == K_ARRAY) && mv != NULL && mv->seen != NULL &&
        packed_at(mv, f, offset, value) < 0)
        return -1;
    if (f->code == K_NESTED && Py_TYPE(value) != (PyTypeObject *)f->view_type)
        return pack_members(members, image, offset, value, mv);
    FieldObject *element = f->element;
    if (f->code != K_ARRAY || (element->code != K_NESTED && element->code != K_ARRAY))
        return write_field(f, image, offset, value); /* checked; an array of values whole */
    PyObject *items = PySequence_Fast(value, "an array takes a sequence");
    if (items == NULL) return -1;
    int failed = 0;
    if (PySequence_Fast_GET_SIZE(items) != f->count) {
        PyErr_Format(PyExc_ValueError, "an array of %zd elements cannot take %zd", f->count,
                     PySequence_Fast_GET_SIZE(items));
        failed = -1;
    }
    PyObject *inner = failed ? NULL : nested_members(element, &failed);
    for (Py_ssize_t i = 0; !failed && i < f->count; i++)
        failed = pack_value(element, inner, image, offset + i * f->stride,
                            PySequence_Fast_GET_ITEM(items, i), mv);
    Py_XDECREF(inner);
    Py_DECREF(items);
    return failed ? -1 : 0;
}

static int pack_members(PyObject *members, PyObject *image, Py_ssize_t offset, PyObject *source,
                        moving *mv) {
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(members); i++) {
        PyObject *pair = PyList_GET_ITEM(members, i);
        FieldObject *f = (FieldObject *)PyTuple_GET_ITEM(pair, 1);
        PyObject *value = PyObject_GetAttr(source, PyTuple_GET_ITEM(pair, 0));
        if (value == NULL) return -1;
        int failed;
        PyObject *inner = nested_members(f, &failed);
        if (!failed) failed = pack_value(f, inner, image, offset + f->offset, value, mv);
        Py_XDECREF(inner);
        Py_DECREF(value);
        if (failed) return -1;
    }
    return 0;
}

/* Each in-out packed bound: to where its object was packed, when it was and is of its type;
 * else its object into its own storage (the object of its own, or one no variable holds),
 * where another in-out given the same object finds it too. Pending entries may grow on
 * the way (an array of blocks with in-outs of their own). */
static int bind_packed(moving *mv, PyObject *image) {
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(mv->pending); i++) {
        PyObject *entry = PyList_GET_ITEM(mv->pending, i);
        Py_ssize_t offset = PyLong_AsSsize_t(PyTuple_GET_ITEM(entry, 0));
        FieldObject *f = (FieldObject *)PyTuple_GET_ITEM(entry, 1);
        PyObject *object = PyTuple_GET_ITEM(entry, 2);
        PyObject *id = PyLong_FromVoidPtr(object);
        if (id == NULL) return -1;
        PyObject *found = PyDict_GetItemWithError(mv->seen, id);
        Py_DECREF(id);
        if (found == NULL && PyErr_Occurred()) return -1;
        if (found != NULL && same_type((FieldObject *)PyTuple_GET_ITEM(found, 1), f->element)) {
            bind_at(image, offset, PyLong_AsSsize_t(PyTuple_GET_ITEM(found, 0)));
            continue;
        }
        int failed;
        PyObject *inner = nested_members(f->element, &failed);
        if (!failed)
            failed = pack_value(f->element, inner, image, offset + f->own, object, mv) < 0;
        Py_XDECREF(inner);
        if (failed) return -1;
        bind_at(image, offset, offset + f->own);
    }
    return 0;
}

/* The bytes at `offset` into `target`, the instance or list slot objects hold there;
 * `members` as for pack_value. */
static int unpack_into(FieldObject *f, PyObject *members, PyObject *image, Py_ssize_t offset,
                       PyObject *target, moving *mv) {
    if (field_cleared(f)) return -1;
    if (mv != NULL && mv->seen != NULL &&
        remember(mv, place_key(f, offset), Py_NewRef(target)) < 0)
        return -1;
    if (f->code == K_NESTED) return unpack_members(members, image, offset, target, mv);
    FieldObject *element = f->element;
    int failed;
    PyObject *inner = nested_members(element, &failed);
    for (Py_ssize_t i = 0; !failed && i < f->count; i++) {
        Py_ssize_t at_i = offset + i * f->stride;
        if (element->code == K_NESTED || element->code == K_ARRAY) {
            PyObject *item = PySequence_GetItem(target, i);
            failed = item == NULL || unpack_into(element, inner, image, at_i, item, mv) < 0;
            Py_XDECREF(item);
        } else {
            PyObject *value = read_field(element, image, at_i);
            failed = value == NULL || PySequence_SetItem(target, i, value) < 0;
            Py_XDECREF(value);
        }
    }
    Py_XDECREF(inner);
    return failed ? -1 : 0;
}

static int unpack_members(PyObject *members, PyObject *image, Py_ssize_t offset, PyObject *target,
                          moving *mv) {
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(members); i++) {
        PyObject *pair = PyList_GET_ITEM(members, i);
        PyObject *name = PyTuple_GET_ITEM(pair, 0);
        FieldObject *f = (FieldObject *)PyTuple_GET_ITEM(pair, 1);
        int failed;
        if (f->code == K_BOUND) {
            if (mv == NULL) {
                PyErr_SetString(PyExc_TypeError, "an instance with in-outs taken whole");
                return -1;
            }
            PyObject *entry = Py_BuildValue("(nOOO)", offset + f->offset, f, target, name);
            failed = entry == NULL || PyList_Append(mv->pending, entry) < 0;
            Py_XDECREF(entry);
        } else if (f->code == K_NESTED || f->code == K_ARRAY) {
            PyObject *held = PyObject_GetAttr(target, name);
            PyObject *inner = held == NULL ? NULL : nested_members(f, &failed);
            if (held == NULL) failed = 1;
            if (!failed) failed = unpack_into(f, inner, image, offset + f->offset, held, mv) < 0;
            Py_XDECREF(inner);
            Py_XDECREF(held);
        } else {
            PyObject *value = read_field(f, image, offset + f->offset);
            failed = value == NULL || PyObject_SetAttr(target, name, value) < 0;
            Py_XDECREF(value);
        }
        if (failed) return -1;
    }
    return 0;
}

/* Each in-out unpacked: first those bound to their own storage, whose values go into the
 * object the fresh instance holds of its own; then every other, given the object unpacked
 * where it is bound, as the slot tier holds the caller's very object. One bound where no
 * object was unpacked (a defect) gets the values into an object of its own. */
static int bind_unpacked(moving *mv, PyObject *image) {
    for (int own_first = 1; own_first >= 0; own_first--) {
        for (Py_ssize_t i = 0; i < PyList_GET_SIZE(mv->pending); i++) {
            PyObject *entry = PyList_GET_ITEM(mv->pending, i);
            Py_ssize_t offset = PyLong_AsSsize_t(PyTuple_GET_ITEM(entry, 0));
            FieldObject *f = (FieldObject *)PyTuple_GET_ITEM(entry, 1);
            PyObject *holder = PyTuple_GET_ITEM(entry, 2), *name = PyTuple_GET_ITEM(entry, 3);
            Py_ssize_t target = bound_target(f, image, offset);
            if (target < 0) return -1;
            if ((target == offset + f->own) != own_first) continue;
            PyObject *key = place_key(f->element, target);
            if (key == NULL) return -1;
            PyObject *found = own_first ? NULL : PyDict_GetItemWithError(mv->seen, key);
            Py_DECREF(key);
            if (found == NULL && PyErr_Occurred()) return -1;
            if (found != NULL) {
                if (PyObject_SetAttr(holder, name, found) < 0) return -1;
                continue;
            }
            PyObject *own = PyObject_GetAttr(holder, name);
            int failed = own == NULL;
            PyObject *inner = failed ? NULL : nested_members(f->element, &failed);
            if (!failed) failed = unpack_into(f->element, inner, image, target, own, mv) < 0;
            Py_XDECREF(inner);
            Py_XDECREF(own);
            if (failed) return -1;
        }
    }
    return 0;
}

/* pack or unpack of [(view, object)]: a configuration's instances, all of one image;
 * `in_outs`: whether any of its classes has an in-out (the identity map costs a third of
 * the move where none has). */
static PyObject *move(PyObject *args, int packing) {
    PyObject *pairs;
    int in_outs = 1;
    if (!PyArg_ParseTuple(args, "O!|p", &PyList_Type, &pairs, &in_outs)) return NULL;
    moving mv = {in_outs ? PyDict_New() : NULL, PyList_New(0)};
    PyObject *image = NULL;
    int failed = (in_outs && mv.seen == NULL) || mv.pending == NULL;
    for (Py_ssize_t i = 0; !failed && i < PyList_GET_SIZE(pairs); i++) {
        PyObject *pair = PyList_GET_ITEM(pairs, i), *view, *object;
        if (!PyArg_ParseTuple(pair, "O!O", &ViewType, &view, &object)) {
            failed = 1;
            break;
        }
        ViewObject *v = (ViewObject *)view;
        if (image != NULL && v->image != image) {
            PyErr_SetString(PyExc_ValueError, "views of two images");
            failed = 1;
            break;
        }
        image = v->image;
        PyObject *members = members_of((PyObject *)Py_TYPE(view));
        failed = members == NULL ||
                 (packing ? pack_members(members, image, v->offset, object, &mv)
                          : unpack_members(members, image, v->offset, object, &mv)) < 0;
        Py_XDECREF(members);
    }
    if (!failed && image != NULL && PyList_GET_SIZE(mv.pending) > 0 && mv.seen == NULL) {
        PyErr_SetString(PyExc_ValueError, "in-outs moved without their identity map");
        failed = 1;
    }
    if (!failed && image != NULL)
        failed = (packing ? bind_packed(&mv, image) : bind_unpacked(&mv, image)) < 0;
    Py_XDECREF(mv.seen);
    Py_XDECREF(mv.pending);
    if (failed) return NULL;
    Py_RETURN_NONE;
}

static PyObject *pack(PyObject *module, PyObject *args) { return move(args, 1); }
static PyObject *unpack(PyObject *module, PyObject *args) { return move(args, 0); }

static PyMethodDef module_methods[] = {
    {"pack", pack, METH_VARARGS,
     "pack([(view, object)], in_outs=True): every value of slot objects (their instances and "
     "arrays too) into the views' bytes, each checked as a store is; an in-out bound where "
     "the object it holds went."},
    {"unpack", unpack, METH_VARARGS,
     "unpack([(view, object)], in_outs=True): every value of the views into slot objects of "
     "their classes and the instances and arrays they hold; an in-out given the object "
     "unpacked where it is bound."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, .m_name = "padt_memory", .m_size = -1, .m_methods = module_methods,
};

PyMODINIT_FUNC PADT_INIT(void) {
    if (PyType_Ready(&ViewType) < 0 || PyType_Ready(&FieldType) < 0 ||
        PyType_Ready(&ElementsType) < 0)
        return NULL;
    PyObject *m = PyModule_Create(&module);
    if (m == NULL) return NULL;
    if (PyModule_AddObjectRef(m, "View", (PyObject *)&ViewType) < 0 ||
        PyModule_AddObjectRef(m, "Field", (PyObject *)&FieldType) < 0 ||
        PyModule_AddObjectRef(m, "Elements", (PyObject *)&ElementsType) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}

/* The usual CPU cycle of a resource in C (docs/native-code.md, "The CPU cycle in C"):
 * what `Resource.cycle`, `Resource.run_programs`, `Scheduler.run`, `UserProgram.run_whole`,
 * `CycleStats.record` and `record_period` and the watchdog's `arm` and `disarm` do when
 * nothing unusual happens, on the same Python objects. The Python is the reference: this
 * file follows it line by line, and every branch that is not the usual cycle calls the
 * Python that handles it (the inputs the I/O delivered, the output image, a program's
 * fault, an Emergency Stop, the watchdog striking, Force Deactivation, a recording).
 *
 * `Core.cycle()` is True once it has run the cycle, False when the cycle is not a usual
 * one (not RUN, forcing started, a debugger, a recording, a tap, a program with a time
 * slice or in the middle of its program cycle), decided before anything changes: the
 * resource then runs its Python cycle.
 *
 * Speed comes from the objects' slots (CycleStats, SystemView, UserProgram,
 * ProgramCycleStats have __slots__): a member is read and written at its offset, found
 * once from the class's member descriptor. A value is an int64 only while it is one: an
 * integer out of that range takes the Python method (`record`, `record_period`), which
 * computes with Python's integers.
 *
 * Included after `#define PADT_INIT PyInit_<module name>` (build.py's `runtime_module` names
 * the module by the hash of its source).
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#include <time.h>

#define SLOT(obj, off) (*(PyObject **)((char *)(obj) + (off)))

/* The members of each slotted class, by name; their offsets are found at Core(). */
static const char *SYSTEM_NAMES[] = {
    "now_ns", "COLDSTART", "WARMSTART", "START_CYCLE", "CYCLE_TIME_LAST", "CYCLE_TIME_MIN",
    "CYCLE_TIME_MAX", "CYCLE_TIME_MEAN", "SYSTEM_TICK", "FORCE_TIME_REMAINING",
    "DATE_AND_TIME", "FORCE_DEACTIVATION", "EMERGENCY_STOP_1", "EMERGENCY_STOP_2",
    "EMERGENCY_STOP_3", "EMERGENCY_STOP_4", NULL};
enum { S_NOW, S_COLD, S_WARM, S_START, S_LAST, S_MIN, S_MAX, S_MEAN, S_TICK, S_FORCE_LEFT,
       S_DT, S_FORCE_OFF, S_ESTOP1, S_COUNT_ = S_ESTOP1 + 4 };

static const char *STATS_NAMES[] = {
    "count", "last_ns", "min_ns", "max_ns", "total_ns", "mean_ns", "overruns",
    "jitter_max_ns", "last_period_ns", NULL};
enum { C_COUNT, C_LAST, C_MIN, C_MAX, C_TOTAL, C_MEAN, C_OVERRUNS, C_JITTER, C_PERIOD,
       C_COUNT_ };

static const char *PROGRAM_NAMES[] = {
    "state", "run", "whole", "last_start_ns", "stats", "view", "time_ns", "cycle_time_ns",
    "cpu_cycles", "instance", "config", NULL};
enum { P_STATE, P_RUN, P_WHOLE, P_LAST_START, P_STATS, P_VIEW, P_TIME, P_CYCLE_TIME,
       P_CPU_CYCLES, P_INSTANCE, P_CONFIG, P_COUNT_ };

static const char *PSTATS_NAMES[] = {"count", "last_cpu_cycles", "max_cpu_cycles", NULL};
enum { Q_COUNT, Q_LAST, Q_MAX, Q_COUNT_ };

/* The members of the resource and of its parts that the cycle reads or writes. */
static const char *RESOURCE_NAMES[] = {
    "state", "recordings", "stats", "params", "_last_start_ns", "_first_cycle", "start_kind",
    "_boot_ns", "cycle_count", NULL};
enum { R_STATE, R_RECORDINGS, R_STATS, R_PARAMS, R_LAST_START, R_FIRST, R_START_KIND, R_BOOT,
       R_CYCLE_COUNT, R_COUNT_ };
static const char *VARIABLES_NAMES[] = {"tap", "code", "globals", "programs", "outputs", NULL};
enum { V_TAP, V_CODE, V_GLOBALS, V_PROGRAMS, V_OUTPUTS, V_COUNT_ };
static const char *FORCING_NAMES[] = {"table", "deactivated", NULL};
enum { F_TABLE, F_DEACTIVATED, F_COUNT_ };
static const char *TABLE_NAMES[] = {"levels", NULL};
static const char *DEBUGGER_NAMES[] = {"active", NULL};
static const char *SCHEDULER_NAMES[] = {"used_ns", NULL};
static const char *WATCHDOG_NAMES[] = {"_budget_ns", "_next_look_ns", "_wake", NULL};
enum { W_BUDGET, W_NEXT_LOOK, W_WAKE, W_COUNT_ };
static const char *IO_NAMES[] = {"delivered", "outputs", NULL};
enum { I_DELIVERED, I_OUTPUTS, I_COUNT_ };

enum { CLOCK_REAL, CLOCK_VIRTUAL };

typedef struct {
    PyObject_HEAD
    /* the resource and its parts that are never replaced (Resource.__init__ makes them) */
    PyObject *resource, *clock, *io, *forcing, *debugger, *variables, *scheduler, *watchdog;
    PyObject *system, *deadlines; /* the watchdog's armed deadlines, by thread */
    int clock_kind;
    /* the slotted classes, with their members' offsets */
    PyTypeObject *system_type, *stats_type, *program_type, *pstats_type, *table_type;
    Py_ssize_t sys_off[S_COUNT_], stats_off[C_COUNT_], prog_off[P_COUNT_], pstats_off[Q_COUNT_];
    Py_ssize_t res_off[R_COUNT_], var_off[V_COUNT_], forcing_off[F_COUNT_], table_off[1];
    Py_ssize_t debugger_off[1], scheduler_off[1], watchdog_off[W_COUNT_], io_off[I_COUNT_];
    /* constants: ResourceState.RUN and RUN_UP_STOP, ProgramState.RUN, the plain call's
     * marker, copy_globals, WatchdogExpired, Halted, the overrun tolerance's least */
    PyObject *running1, *running2, *program_run, *direct, *copy_globals;
    PyObject *watchdog_expired, *halted;
    int64_t min_tolerance_ns;
} Core;

/* Attribute names, interned once. */
static PyObject *N_active, *N_read_inputs, *N_target_ms, *N_levels, *N_namespace,
    *N_watchdog_ms, *N_set, *N_disarm, *N_cycle_ns, *N_program_fault,
    *N_emergency_stopped, *N_watchdog_expired_m, *N_publish, *N_check_deactivation,
    *N_apply, *N_write_outputs, *N_record, *N_record_period, *N_cycled, *N_now,
    *N_epoch, *N_reads, *N_G, *N_tick, *N_cold, *N_warm;

static PyObject *ZERO, *ONE; /* the ints 0 and 1 */

static const struct {
    PyObject **name;
    const char *text;
} NAMES[] = {
    {&N_active, "active"},
    {&N_read_inputs, "read_inputs"},
    {&N_target_ms, "target_cycle_ms"},
    {&N_levels, "levels"},
    {&N_namespace, "namespace"},
    {&N_watchdog_ms, "watchdog_ms"},
    {&N_set, "set"},
    {&N_disarm, "disarm"},
    {&N_cycle_ns, "cycle_ns"},
    {&N_program_fault, "_program_fault"},
    {&N_emergency_stopped, "emergency_stopped"},
    {&N_watchdog_expired_m, "_watchdog_expired"},
    {&N_publish, "publish"},
    {&N_check_deactivation, "check_deactivation"},
    {&N_apply, "apply"},
    {&N_write_outputs, "write_outputs"},
    {&N_record, "record"},
    {&N_record_period, "record_period"},
    {&N_cycled, "cycled"},
    {&N_now, "_now"},
    {&N_epoch, "_epoch"},
    {&N_reads, "reads"},
    {&N_G, "_G"},
    {&N_tick, "_tick"},
    {&N_cold, "cold"},
    {&N_warm, "warm"},
};

static int intern_names(void) {
    if (ZERO == NULL && (ZERO = PyLong_FromLong(0)) == NULL)
        return -1;
    if (ONE == NULL && (ONE = PyLong_FromLong(1)) == NULL)
        return -1;
    for (size_t i = 0; i < sizeof NAMES / sizeof NAMES[0]; i++)
        if (*NAMES[i].name == NULL &&
            (*NAMES[i].name = PyUnicode_InternFromString(NAMES[i].text)) == NULL)
            return -1;
    return 0;
}

/* ---- slots */

static int offsets_of(PyTypeObject *type, const char **names, Py_ssize_t *offsets) {
    for (int i = 0; names[i] != NULL; i++) {
        PyObject *found = PyObject_GetAttrString((PyObject *)type, names[i]);
        if (found == NULL)
            return -1;
        int slot = Py_IS_TYPE(found, &PyMemberDescr_Type) &&
                   ((PyMemberDescrObject *)found)->d_member->type == T_OBJECT_EX;
        if (slot)
            offsets[i] = ((PyMemberDescrObject *)found)->d_member->offset;
        Py_DECREF(found);
        if (!slot) {
            PyErr_Format(PyExc_TypeError, "%s.%s is no slot", type->tp_name, names[i]);
            return -1;
        }
    }
    return 0;
}

/* A slot's value, borrowed; NULL with AttributeError when it was never set. */
static inline PyObject *get(PyObject *obj, Py_ssize_t off, const char *name) {
    PyObject *value = SLOT(obj, off);
    if (value == NULL)
        PyErr_Format(PyExc_AttributeError, "'%s' object has no attribute '%s'",
                     Py_TYPE(obj)->tp_name, name);
    return value;
}

/* Store a new reference (taken) into a slot. */
static inline void put(PyObject *obj, Py_ssize_t off, PyObject *value) {
    PyObject *old = SLOT(obj, off);
    SLOT(obj, off) = value;
    Py_XDECREF(old);
}

static inline void put_borrowed(PyObject *obj, Py_ssize_t off, PyObject *value) {
    put(obj, off, Py_NewRef(value));
}

/* An exact int that fits an int64; 0 otherwise (no error set). */
static inline int as_i64(PyObject *value, int64_t *out) {
    if (value == NULL || !PyLong_CheckExact(value))
        return 0;
    int overflow = 0;
    long long x = PyLong_AsLongLongAndOverflow(value, &overflow);
    if (overflow || (x == -1 && PyErr_Occurred())) {
        PyErr_Clear();
        return 0;
    }
    *out = x;
    return 1;
}

/* Store an int64 as a Python int; -1 on error. */
static inline int put_i64(PyObject *obj, Py_ssize_t off, int64_t value) {
    PyObject *boxed = PyLong_FromLongLong(value);
    if (boxed == NULL)
        return -1;
    put(obj, off, boxed);
    return 0;
}

static PyObject *getattr(PyObject *obj, PyObject *name) { return PyObject_GetAttr(obj, name); }

/* obj.name is true; -1 on error. */
static int attr_true(PyObject *obj, PyObject *name) {
    PyObject *value = PyObject_GetAttr(obj, name);
    if (value == NULL)
        return -1;
    int truth = PyObject_IsTrue(value);
    Py_DECREF(value);
    return truth;
}

/* ---- clocks: what RealClock's C functions read (time.monotonic_ns, time.time_ns) */

static int64_t clock_ns(clockid_t id) {
    struct timespec now;
    clock_gettime(id, &now);
    return (int64_t)now.tv_sec * 1000000000 + now.tv_nsec;
}

/* clock.now_ns(), or VirtualClock's `_now`; -1 with an error set when it is no int64. */
static int now_of(Core *core, int64_t *out) {
    if (core->clock_kind == CLOCK_REAL) {
        *out = clock_ns(CLOCK_MONOTONIC);
        return 0;
    }
    PyObject *now = getattr(core->clock, N_now);
    int ok = as_i64(now, out);
    Py_XDECREF(now);
    if (!ok && !PyErr_Occurred())
        PyErr_SetString(PyExc_OverflowError, "the virtual clock is beyond 64 bits");
    return ok ? 0 : -1;
}

static PyObject *wall_of(Core *core) {
    if (core->clock_kind == CLOCK_REAL)
        return PyLong_FromLongLong(clock_ns(CLOCK_REALTIME));
    PyObject *epoch = getattr(core->clock, N_epoch);
    if (epoch == NULL)
        return NULL;
    PyObject *now = getattr(core->clock, N_now);
    if (now == NULL) {
        Py_DECREF(epoch);
        return NULL;
    }
    PyObject *wall = PyNumber_Add(epoch, now);
    Py_DECREF(epoch);
    Py_DECREF(now);
    return wall;
}

/* ---- the cycle */

/* What the usual cycle needs, fetched before anything changes. */
typedef struct {
    PyObject *stats;    /* resource.stats */
    PyObject *params;   /* resource.params */
    PyObject *programs; /* variables.programs (a list) */
    PyObject *names;    /* the code's namespace */
    PyObject *master;   /* variables.globals */
    PyObject *recordings;
    int64_t budget_ns;  /* the watchdog time */
} Usual;

static void usual_clear(Usual *u) {
    Py_CLEAR(u->stats);
    Py_CLEAR(u->params);
    Py_CLEAR(u->programs);
    Py_CLEAR(u->names);
    Py_CLEAR(u->master);
    Py_CLEAR(u->recordings);
}

/* A member of the resource or of one of its parts, by its offset (borrowed). */
#define RES(core, i) get((core)->resource, (core)->res_off[i], RESOURCE_NAMES[i])
#define VAR(core, i) get((core)->variables, (core)->var_off[i], VARIABLES_NAMES[i])

/* A value's truth; -1 on error (NULL: an error already set). */
static inline int truth(PyObject *value) {
    if (value == Py_False || value == Py_None)
        return 0;
    if (value == Py_True)
        return 1;
    return value == NULL ? -1 : PyObject_IsTrue(value);
}

/* 1: the usual cycle; 0: the Python cycle's; -1: an error. */
static int is_usual(Core *core, Usual *u) {
    PyObject *state = RES(core, R_STATE);
    if (state == NULL)
        return -1;
    if (state != core->running1 && state != core->running2)
        return 0;
    PyObject *recordings = RES(core, R_RECORDINGS);
    if (recordings == NULL)
        return -1;
    u->recordings = Py_NewRef(recordings);
    if (recordings != Py_None) {
        int active = attr_true(recordings, N_active);
        if (active != 0)
            return active < 0 ? -1 : 0;
    }
    PyObject *table = get(core->forcing, core->forcing_off[F_TABLE], "table");
    if (table == NULL)
        return -1;
    if (!Py_IS_TYPE(table, core->table_type))
        return 0;
    int forcing = truth(get(table, core->table_off[0], "levels"));
    if (forcing != 0)
        return forcing < 0 ? -1 : 0;
    int debugged = truth(get(core->debugger, core->debugger_off[0], "active"));
    if (debugged != 0)
        return debugged < 0 ? -1 : 0;
    PyObject *tap = VAR(core, V_TAP);
    if (tap == NULL)
        return -1;
    if (tap != Py_None)
        return 0;
    PyObject *stats = RES(core, R_STATS);
    if (stats == NULL)
        return -1;
    if (!Py_IS_TYPE(stats, core->stats_type))
        return 0;
    u->stats = Py_NewRef(stats);
    PyObject *params = RES(core, R_PARAMS);
    if (params == NULL)
        return -1;
    u->params = Py_NewRef(params);
    PyObject *watchdog_ms = getattr(params, N_watchdog_ms);
    int64_t ms = 0;
    int fits = as_i64(watchdog_ms, &ms) && ms >= 0 && ms <= INT64_MAX / 1000000 / 2;
    Py_XDECREF(watchdog_ms);
    if (!fits)
        return PyErr_Occurred() ? -1 : 0;
    u->budget_ns = ms * 1000000;
    PyObject *code = VAR(core, V_CODE);
    if (code == NULL)
        return -1;
    if (code == Py_None)
        return 0;
    if ((u->names = getattr(code, N_namespace)) == NULL)
        return -1;
    if (!PyDict_CheckExact(u->names))
        return 0;
    PyObject *master = VAR(core, V_GLOBALS), *programs = VAR(core, V_PROGRAMS);
    if (master == NULL || programs == NULL)
        return -1;
    if (!PyList_CheckExact(programs))
        return 0;
    u->master = Py_NewRef(master);
    u->programs = Py_NewRef(programs);
    /* every program that runs: no time slice, no debugging, no program cycle in progress */
    for (Py_ssize_t i = 0; i < PyList_GET_SIZE(programs); i++) {
        PyObject *program = PyList_GET_ITEM(programs, i);
        if (!Py_IS_TYPE(program, core->program_type))
            return 0;
        PyObject *pstate = get(program, core->prog_off[P_STATE], "state");
        if (pstate == NULL)
            return -1;
        if (pstate != core->program_run)
            continue;
        PyObject *run = get(program, core->prog_off[P_RUN], "run");
        PyObject *whole = get(program, core->prog_off[P_WHOLE], "whole");
        PyObject *stats = get(program, core->prog_off[P_STATS], "stats");
        if (run == NULL || whole == NULL || stats == NULL)
            return -1;
        if (run != Py_None || whole != Py_True || !Py_IS_TYPE(stats, core->pstats_type))
            return 0;
    }
    return 1;
}

/* ---- calls of the Python that handles what is not usual */

static int call0(PyObject *obj, PyObject *name) {
    PyObject *result = PyObject_CallMethodNoArgs(obj, name);
    Py_XDECREF(result);
    return result == NULL ? -1 : 0;
}

static int call1(PyObject *obj, PyObject *name, PyObject *arg) {
    PyObject *result = PyObject_CallMethodOneArg(obj, name, arg);
    Py_XDECREF(result);
    return result == NULL ? -1 : 0;
}

static int call2(PyObject *obj, PyObject *name, PyObject *a, PyObject *b) {
    PyObject *result = PyObject_CallMethodObjArgs(obj, name, a, b, NULL);
    Py_XDECREF(result);
    return result == NULL ? -1 : 0;
}

/* Python's floor division of int64s (b > 0). */
static inline int64_t floor_div(int64_t a, int64_t b) {
    int64_t q = a / b;
    return (a % b != 0 && a < 0) ? q - 1 : q;
}

/* CycleStats.record_period(begin - last, target_cycle_ms * 1_000_000). */
static int record_period(Core *core, PyObject *stats, PyObject *params, PyObject *begin,
                         PyObject *last) {
    PyObject *target_ms = getattr(params, N_target_ms);
    if (target_ms == NULL)
        return -1;
    int64_t b, l, ms, jitter, overruns, period, target, deviation;
    if (as_i64(begin, &b) && as_i64(last, &l) && as_i64(target_ms, &ms) && ms >= 0 &&
        ms <= INT64_MAX / 1000000 / 4 &&
        as_i64(SLOT(stats, core->stats_off[C_JITTER]), &jitter) &&
        as_i64(SLOT(stats, core->stats_off[C_OVERRUNS]), &overruns) &&
        !__builtin_sub_overflow(b, l, &period) && period > INT64_MIN / 2 &&
        period < INT64_MAX / 2) {
        Py_DECREF(target_ms);
        target = ms * 1000000;
        if (put_i64(stats, core->stats_off[C_PERIOD], period) < 0)
            return -1;
        if (target) {
            deviation = period > target ? period - target : target - period;
            if (deviation > jitter && put_i64(stats, core->stats_off[C_JITTER], deviation) < 0)
                return -1;
            int64_t tolerance = target / 4 > core->min_tolerance_ns ? target / 4
                                                                   : core->min_tolerance_ns;
            if (period > target + tolerance &&
                put_i64(stats, core->stats_off[C_OVERRUNS], overruns + 1) < 0)
                return -1;
        }
        return 0;
    }
    /* beyond 64 bits: Python's integers */
    PyObject *million = PyLong_FromLong(1000000);
    PyObject *target_ns = million ? PyNumber_Multiply(target_ms, million) : NULL;
    PyObject *difference = target_ns ? PyNumber_Subtract(begin, last) : NULL;
    int failed = difference == NULL || call2(stats, N_record_period, difference, target_ns) < 0;
    Py_XDECREF(million);
    Py_XDECREF(target_ns);
    Py_XDECREF(difference);
    Py_DECREF(target_ms);
    return failed ? -1 : 0;
}

/* CycleStats.record(duration). */
static int record(Core *core, PyObject *stats, PyObject *duration) {
    const Py_ssize_t *off = core->stats_off;
    int64_t d, count, min, max, total;
    if (as_i64(duration, &d) && as_i64(SLOT(stats, off[C_COUNT]), &count) &&
        as_i64(SLOT(stats, off[C_MIN]), &min) && as_i64(SLOT(stats, off[C_MAX]), &max) &&
        as_i64(SLOT(stats, off[C_TOTAL]), &total) && count < INT64_MAX &&
        !__builtin_add_overflow(total, d, &total)) {
        count += 1;
        if (put_i64(stats, off[C_COUNT], count) < 0)
            return -1;
        put_borrowed(stats, off[C_LAST], duration);
        if (d < min || count == 1)
            put_borrowed(stats, off[C_MIN], duration);
        if (d > max)
            put_borrowed(stats, off[C_MAX], duration);
        if (put_i64(stats, off[C_TOTAL], total) < 0)
            return -1;
        return put_i64(stats, off[C_MEAN], floor_div(total, count));
    }
    return call1(stats, N_record, duration);
}

/* UserProgram.run_whole(delta, master, system, names): 0, or -1 with what the program (or
 * the copy of its globals) raised. */
static int run_whole(Core *core, Usual *u, PyObject *program, PyObject *delta) {
    const Py_ssize_t *off = core->prog_off, *q = core->pstats_off;
    PyObject *system = core->system;
    PyObject *stats = get(program, off[P_STATS], "stats");
    if (stats == NULL)
        return -1;
    Py_INCREF(stats);
    int failed = -1;
    PyObject *view = NULL, *instance = NULL;
    PyObject *count = get(stats, q[Q_COUNT], "count");
    if (count == NULL)
        goto end;
    int64_t n;
    int counted = as_i64(count, &n) ? n > 0 : PyObject_RichCompareBool(count, ZERO, Py_GT);
    if (counted < 0)
        goto end;
    if (counted) {
        PyObject *time = get(program, off[P_TIME], "time_ns");
        if (time == NULL)
            goto end;
        PyObject *later = PyNumber_Add(time, delta);
        if (later == NULL)
            goto end;
        put(program, off[P_TIME], later);
    }
    PyObject *time = get(program, off[P_TIME], "time_ns");
    if (time == NULL)
        goto end;
    put_borrowed(system, core->sys_off[S_NOW], time);
    put_borrowed(program, off[P_CYCLE_TIME], time);
    view = get(program, off[P_VIEW], "view");
    if (view == NULL)
        goto end;
    Py_INCREF(view);
    if (view != u->master) { /* its own view of the globals: what it reads, copied in */
        PyObject *config = get(program, off[P_CONFIG], "config");
        PyObject *reads = config ? getattr(config, N_reads) : NULL;
        PyObject *copied =
            reads ? PyObject_CallFunctionObjArgs(core->copy_globals, u->master, view, reads, NULL)
                  : NULL;
        Py_XDECREF(reads);
        if (copied == NULL)
            goto end;
        Py_DECREF(copied);
    }
    if (PyDict_SetItem(u->names, N_G, view) < 0 || PyDict_SetItem(u->names, N_tick, Py_None) < 0)
        goto end;
    put_borrowed(program, off[P_RUN], core->direct); /* in progress: the watchdog names it */
    put(program, off[P_CPU_CYCLES], PyLong_FromLong(1));
    instance = get(program, off[P_INSTANCE], "instance");
    if (instance == NULL)
        goto end;
    Py_INCREF(instance);
    PyObject *result = PyObject_CallNoArgs(instance);
    if (result == NULL)
        goto end;
    Py_DECREF(result);
    count = get(stats, q[Q_COUNT], "count");
    if (count == NULL)
        goto end;
    PyObject *more = as_i64(count, &n) && n < INT64_MAX ? PyLong_FromLongLong(n + 1)
                                                         : PyNumber_Add(count, ONE);
    if (more == NULL)
        goto end;
    put(stats, q[Q_COUNT], more);
    put(stats, q[Q_LAST], PyLong_FromLong(1));
    PyObject *most = get(stats, q[Q_MAX], "max_cpu_cycles");
    int truth = most ? PyObject_IsTrue(most) : -1;
    if (truth < 0)
        goto end;
    if (!truth)
        put(stats, q[Q_MAX], PyLong_FromLong(1));
    put_borrowed(program, off[P_RUN], Py_None);
    failed = 0;
end:
    Py_DECREF(stats);
    Py_XDECREF(view);
    Py_XDECREF(instance);
    return failed;
}

/* After the watchdog is disarmed: an exception of the programs' part. Halted: 0;
 * WatchdogExpired: `_watchdog_expired`, then 0; anything else stays raised: -1. */
static int halted_by(Core *core) {
    if (PyErr_ExceptionMatches(core->halted)) {
        PyErr_Clear();
        return 0;
    }
    if (!PyErr_ExceptionMatches(core->watchdog_expired))
        return -1;
    PyObject *type, *value, *traceback;
    PyErr_Fetch(&type, &value, &traceback);
    PyErr_NormalizeException(&type, &value, &traceback);
    if (traceback != NULL)
        PyException_SetTraceback(value, traceback);
    int failed = call1(core->scheduler, N_watchdog_expired_m, value);
    Py_XDECREF(type);
    Py_XDECREF(value);
    Py_XDECREF(traceback);
    return failed;
}

/* Watchdog.disarm: 1 when the watchdog fired, 0 when claimed in time, -1 on error. The
 * deadline claimed with one dictionary removal, as `dict.pop` claims it (no Python runs in
 * between); when the watchdog claimed it first, its Python `disarm` waits for it. */
static int disarm(Core *core, PyObject *ident) {
    PyObject *armed = PyDict_GetItemWithError(core->deadlines, ident);
    if (armed != NULL && armed != Py_None)
        return PyDict_DelItem(core->deadlines, ident) < 0 ? -1 : 0;
    if (PyErr_Occurred())
        return -1;
    PyObject *fired = PyObject_CallMethodNoArgs(core->watchdog, N_disarm);
    if (fired == NULL)
        return -1;
    int truth = PyObject_IsTrue(fired);
    Py_DECREF(fired);
    return truth;
}

/* Watchdog.arm(budget). */
static int arm(Core *core, PyObject *ident, int64_t budget) {
    const Py_ssize_t *w = core->watchdog_off;
    int64_t due = clock_ns(CLOCK_MONOTONIC) + budget, look;
    PyObject *deadline = PyLong_FromLongLong(due);
    if (deadline == NULL)
        return -1;
    int failed = PyDict_SetItem(core->deadlines, ident, deadline) < 0;
    PyObject *budget_ns = failed ? NULL : PyLong_FromLongLong(budget);
    if (budget_ns != NULL)
        put(core->watchdog, w[W_BUDGET], budget_ns);
    PyObject *next_look = budget_ns ? get(core->watchdog, w[W_NEXT_LOOK], "_next_look_ns") : NULL;
    int earlier = next_look == NULL          ? -1
                  : as_i64(next_look, &look) ? due < look
                                             : PyObject_RichCompareBool(deadline, next_look, Py_LT);
    Py_DECREF(deadline);
    if (earlier < 0)
        return -1;
    if (earlier) { /* a shorter budget than the watchdog thread sleeps for */
        PyObject *wake = get(core->watchdog, w[W_WAKE], "_wake");
        return wake ? call0(wake, N_set) : -1;
    }
    return 0;
}

/* Scheduler.run for programs without a time slice: 1 ran, 0 the resource halted, -1 an
 * error. */
static int scheduler_run(Core *core, Usual *u, PyObject *begin, PyObject *finished) {
    PyObject *ident = PyLong_FromUnsignedLong(PyThread_get_thread_ident());
    if (ident == NULL)
        return -1;
    if (arm(core, ident, u->budget_ns) < 0) {
        Py_DECREF(ident);
        return halted_by(core);
    }
    put_borrowed(core->scheduler, core->scheduler_off[0], ZERO);
    int failed = 0;
    int halted = 0;
    const Py_ssize_t *off = core->prog_off;
    PyObject *system = core->system;
    for (Py_ssize_t i = 0; !failed && !halted && i < PyList_GET_SIZE(u->programs); i++) {
        PyObject *program = PyList_GET_ITEM(u->programs, i);
        Py_INCREF(program);
        PyObject *state = get(program, off[P_STATE], "state");
        if (state == NULL || state != core->program_run) {
            failed = state == NULL;
            Py_DECREF(program);
            continue;
        }
        /* a new program cycle: its time advances by the clock's since its last one */
        PyObject *last = get(program, off[P_LAST_START], "last_start_ns");
        PyObject *delta = NULL;
        if (last != NULL) {
            Py_INCREF(last);
            put_borrowed(program, off[P_LAST_START], begin);
            delta = last == Py_None ? getattr(core->resource, N_cycle_ns)
                                    : PyNumber_Subtract(begin, last);
            Py_DECREF(last);
        }
        if (delta == NULL) {
            failed = 1;
        } else if (run_whole(core, u, program, delta) == 0) {
            failed = PyList_Append(finished, program) < 0;
        } else if (PyErr_ExceptionMatches(PyExc_Exception)) { /* a run-time error */
            PyObject *type, *value, *traceback;
            PyErr_Fetch(&type, &value, &traceback);
            PyErr_NormalizeException(&type, &value, &traceback);
            if (traceback != NULL)
                PyException_SetTraceback(value, traceback);
            failed = call2(core->scheduler, N_program_fault, program, value) < 0;
            Py_XDECREF(type);
            Py_XDECREF(value);
            Py_XDECREF(traceback);
        } else {
            failed = 1; /* the watchdog, an Emergency Stop: after the disarm */
        }
        Py_XDECREF(delta);
        Py_DECREF(program);
        if (failed)
            break;
        int switched = 0;
        for (int e = 0; e < 4 && !switched; e++) {
            PyObject *on = get(system, core->sys_off[S_ESTOP1 + e], "EMERGENCY_STOP");
            switched = on ? PyObject_IsTrue(on) : -1;
        }
        if (switched) {
            PyObject *stopped = switched < 0 ? NULL
                                              : PyObject_CallMethodNoArgs(core->resource,
                                                                          N_emergency_stopped);
            int truth = stopped ? PyObject_IsTrue(stopped) : -1;
            Py_XDECREF(stopped);
            failed = truth < 0;
            halted = truth > 0;
        }
    }
    /* the disarm, an exception of the programs' part kept aside meanwhile */
    PyObject *type = NULL, *value = NULL, *traceback = NULL;
    if (failed)
        PyErr_Fetch(&type, &value, &traceback);
    int fired = disarm(core, ident);
    Py_DECREF(ident);
    if (failed) {
        if (fired < 0) { /* an error of the disarm replaces the one kept */
            Py_XDECREF(type);
            Py_XDECREF(value);
            Py_XDECREF(traceback);
        } else {
            PyErr_Restore(type, value, traceback);
        }
        return halted_by(core);
    }
    if (fired < 0)
        return halted_by(core);
    if (halted)
        return 0;
    if (fired) { /* it fired just as the work ended: too long all the same */
        PyObject *expired = PyObject_CallNoArgs(core->watchdog_expired);
        int done = expired ? call1(core->scheduler, N_watchdog_expired_m, expired) : -1;
        Py_XDECREF(expired);
        return done < 0 ? -1 : 0;
    }
    return 1;
}

/* Resource.run_programs: 1 ran, 0 halted, -1 error. */
static int run_programs(Core *core, Usual *u, PyObject *begin) {
    PyObject *finished = PyList_New(0);
    if (finished == NULL)
        return -1;
    int ran = scheduler_run(core, u, begin, finished);
    for (Py_ssize_t i = 0; ran > 0 && i < PyList_GET_SIZE(finished); i++) {
        PyObject *program = PyList_GET_ITEM(finished, i);
        PyObject *view = get(program, core->prog_off[P_VIEW], "view");
        if (view == NULL || (view != u->master && call1(program, N_publish, u->master) < 0))
            ran = -1;
    }
    Py_DECREF(finished);
    if (ran <= 0)
        return ran;
    PyObject *off = get(core->system, core->sys_off[S_FORCE_OFF], "FORCE_DEACTIVATION");
    int check = off ? PyObject_IsTrue(off) : -1;
    if (check == 0)
        check = truth(get(core->forcing, core->forcing_off[F_DEACTIVATED], "deactivated"));
    if (check < 0 || (check && call0(core->forcing, N_check_deactivation) < 0))
        return -1;
    PyObject *table = get(core->forcing, core->forcing_off[F_TABLE], "table");
    int forcing = table == NULL                          ? -1
                  : Py_IS_TYPE(table, core->table_type) ? truth(get(table, core->table_off[0],
                                                                    "levels"))
                                                        : attr_true(table, N_levels);
    if (forcing < 0 || (forcing && call0(core->forcing, N_apply) < 0))
        return -1;
    return 1;
}

/* The system variables of a cycle that begins at `begin`. */
static int system_of(Core *core, Usual *u, PyObject *begin) {
    PyObject *system = core->system;
    const Py_ssize_t *s = core->sys_off, *c = core->stats_off;
    PyObject *first = RES(core, R_FIRST);
    if (first == NULL)
        return -1;
    Py_INCREF(first);
    int failed = -1;
    int first_true = PyObject_IsTrue(first);
    PyObject *start = get(system, s[S_START], "START_CYCLE");
    int start_true = first_true == 0 && start != NULL ? PyObject_IsTrue(start) : 0;
    if (first_true < 0 || start == NULL || start_true < 0)
        goto end;
    if (first_true || start_true) { /* set in a start's first cycle, cleared in its second */
        put_borrowed(system, s[S_START], first);
        if (!first_true) {
            put_borrowed(system, s[S_COLD], first);
            put_borrowed(system, s[S_WARM], first);
        } else {
            PyObject *kind = RES(core, R_START_KIND);
            PyObject *cold = kind ? PyObject_RichCompare(kind, N_cold, Py_EQ) : NULL;
            PyObject *warm = cold ? PyObject_RichCompare(kind, N_warm, Py_EQ) : NULL;
            if (warm == NULL) {
                Py_XDECREF(cold);
                goto end;
            }
            put(system, s[S_COLD], cold);
            put(system, s[S_WARM], warm);
        }
    }
    static const int shown[4][2] = {
        {S_LAST, C_LAST}, {S_MIN, C_MIN}, {S_MAX, C_MAX}, {S_MEAN, C_MEAN}};
    for (int i = 0; i < 4; i++) { /* CYCLE_TIME_LAST, MIN, MAX, MEAN: the statistics' */
        PyObject *value = get(u->stats, c[shown[i][1]], STATS_NAMES[shown[i][1]]);
        if (value == NULL)
            goto end;
        put_borrowed(system, s[shown[i][0]], value);
    }
    PyObject *boot = RES(core, R_BOOT);
    if (boot == NULL)
        goto end;
    Py_INCREF(boot);
    int64_t b, since;
    PyObject *tick;
    if (as_i64(begin, &since) && as_i64(boot, &b) && !__builtin_sub_overflow(since, b, &since)) {
        tick = PyLong_FromLongLong(floor_div(since, 1000000) & 0xFFFFFFFF);
    } else { /* ((begin - boot) // 1_000_000) & 0xFFFFFFFF with Python's integers */
        PyObject *million = PyLong_FromLong(1000000), *mask = PyLong_FromUnsignedLong(0xFFFFFFFFu);
        PyObject *difference = million && mask ? PyNumber_Subtract(begin, boot) : NULL;
        PyObject *ms = difference ? PyNumber_FloorDivide(difference, million) : NULL;
        tick = ms ? PyNumber_And(ms, mask) : NULL;
        Py_XDECREF(million);
        Py_XDECREF(mask);
        Py_XDECREF(difference);
        Py_XDECREF(ms);
    }
    Py_DECREF(boot);
    if (tick == NULL)
        goto end;
    put(system, s[S_TICK], tick);
    PyObject *wall = wall_of(core);
    if (wall == NULL)
        goto end;
    put(system, s[S_DT], wall);
    put_borrowed(system, s[S_FORCE_LEFT], ZERO); /* forcing not started */
    failed = 0;
end:
    Py_DECREF(first);
    return failed;
}

/* The cycle itself, once it is known to be a usual one. */
static int usual_cycle(Core *core, Usual *u) {
    PyObject *r = core->resource;
    int64_t now;
    if (now_of(core, &now) < 0)
        return -1;
    PyObject *begin = PyLong_FromLongLong(now);
    if (begin == NULL)
        return -1;
    int failed = -1;
    PyObject *last = NULL;
    int delivered = truth(get(core->io, core->io_off[I_DELIVERED], "delivered"));
    if (delivered < 0 || (delivered && call0(core->io, N_read_inputs) < 0))
        goto end;
    /* (not recording, and RUN: is_usual) */
    if ((last = RES(core, R_LAST_START)) == NULL)
        goto end;
    Py_INCREF(last);
    if (last != Py_None && record_period(core, u->stats, u->params, begin, last) < 0)
        goto end;
    put_borrowed(r, core->res_off[R_LAST_START], begin);
    if (system_of(core, u, begin) < 0)
        goto end;
    /* (no forcing, no debugger, no tap, no recording: is_usual) */
    int ran = run_programs(core, u, begin);
    if (ran <= 0) {
        failed = ran;
        goto end;
    }
    int write = truth(VAR(core, V_OUTPUTS));
    if (write == 0)
        write = truth(get(core->io, core->io_off[I_OUTPUTS], "outputs"));
    if (write < 0 || (write && call1(core->io, N_write_outputs, Py_False) < 0))
        goto end;
    int first = truth(RES(core, R_FIRST));
    if (first < 0)
        goto end;
    if (first) {
        put_borrowed(r, core->res_off[R_FIRST], Py_False);
        put_borrowed(r, core->res_off[R_START_KIND], Py_None);
    }
    PyObject *count = RES(core, R_CYCLE_COUNT);
    int64_t n;
    PyObject *more = count == NULL ? NULL
                     : as_i64(count, &n) && n < INT64_MAX ? PyLong_FromLongLong(n + 1)
                                                           : PyNumber_Add(count, ONE);
    if (more == NULL)
        goto end;
    put(r, core->res_off[R_CYCLE_COUNT], more);
    PyObject *duration;
    if (core->clock_kind == CLOCK_VIRTUAL) { /* what the programs used, in loop passes */
        duration = get(core->scheduler, core->scheduler_off[0], "used_ns");
        Py_XINCREF(duration);
    } else {
        duration = PyLong_FromLongLong(clock_ns(CLOCK_MONOTONIC) - now);
    }
    int recorded = duration ? record(core, u->stats, duration) : -1;
    Py_XDECREF(duration);
    if (recorded < 0)
        goto end;
    if (u->recordings != Py_None) { /* started during the cycle (it was not before) */
        int active = attr_true(u->recordings, N_active);
        if (active < 0)
            goto end;
        if (active) {
            PyObject *before = PyList_New(0), *after = PyList_New(0);
            PyObject *done = before && after ? PyObject_CallMethodObjArgs(
                                                   u->recordings, N_cycled, r, begin, before,
                                                   after, NULL)
                                             : NULL;
            Py_XDECREF(before);
            Py_XDECREF(after);
            if (done == NULL)
                goto end;
            Py_DECREF(done);
        }
    }
    failed = 0;
end:
    Py_DECREF(begin);
    Py_XDECREF(last);
    return failed;
}

static PyObject *Core_cycle(Core *core, PyObject *unused) {
    Usual u = {0};
    int usual = is_usual(core, &u);
    if (usual > 0)
        usual = usual_cycle(core, &u) < 0 ? -1 : 1;
    usual_clear(&u);
    if (usual < 0)
        return NULL;
    return PyBool_FromLong(usual);
}

/* ---- the type */

static PyObject *Core_new(PyTypeObject *type, PyObject *args, PyObject *kwds) {
    PyObject *resource, *clock, *io, *forcing, *debugger, *variables, *scheduler, *watchdog;
    PyObject *system, *deadlines, *classes, *running, *program_run, *direct, *copy_globals;
    PyObject *watchdog_expired, *halted;
    int clock_kind;
    long long min_tolerance_ns;
    if (!PyArg_ParseTuple(args, "OOiOOOOOOOO!O!O!OOOOOL", &resource, &clock, &clock_kind, &io,
                          &forcing, &debugger, &variables, &scheduler, &watchdog, &system,
                          &PyDict_Type, &deadlines, &PyTuple_Type, &classes, &PyTuple_Type,
                          &running, &program_run, &direct, &copy_globals, &watchdog_expired,
                          &halted, &min_tolerance_ns))
        return NULL;
    if (PyTuple_GET_SIZE(classes) != 5 || PyTuple_GET_SIZE(running) != 2 ||
        (clock_kind != CLOCK_REAL && clock_kind != CLOCK_VIRTUAL)) {
        PyErr_SetString(PyExc_TypeError, "Core(): 5 classes, 2 running states, a clock kind");
        return NULL;
    }
    for (int i = 0; i < 5; i++)
        if (!PyType_Check(PyTuple_GET_ITEM(classes, i))) {
            PyErr_SetString(PyExc_TypeError, "Core(): classes are types");
            return NULL;
        }
    if (intern_names() < 0)
        return NULL;
    Core *core = (Core *)type->tp_alloc(type, 0);
    if (core == NULL)
        return NULL;
    core->system_type = (PyTypeObject *)Py_NewRef(PyTuple_GET_ITEM(classes, 0));
    core->stats_type = (PyTypeObject *)Py_NewRef(PyTuple_GET_ITEM(classes, 1));
    core->program_type = (PyTypeObject *)Py_NewRef(PyTuple_GET_ITEM(classes, 2));
    core->pstats_type = (PyTypeObject *)Py_NewRef(PyTuple_GET_ITEM(classes, 3));
    core->table_type = (PyTypeObject *)Py_NewRef(PyTuple_GET_ITEM(classes, 4));
    core->resource = Py_NewRef(resource);
    core->clock = Py_NewRef(clock);
    core->clock_kind = clock_kind;
    core->io = Py_NewRef(io);
    core->forcing = Py_NewRef(forcing);
    core->debugger = Py_NewRef(debugger);
    core->variables = Py_NewRef(variables);
    core->scheduler = Py_NewRef(scheduler);
    core->watchdog = Py_NewRef(watchdog);
    core->system = Py_NewRef(system);
    core->deadlines = Py_NewRef(deadlines);
    core->running1 = Py_NewRef(PyTuple_GET_ITEM(running, 0));
    core->running2 = Py_NewRef(PyTuple_GET_ITEM(running, 1));
    core->program_run = Py_NewRef(program_run);
    core->direct = Py_NewRef(direct);
    core->copy_globals = Py_NewRef(copy_globals);
    core->watchdog_expired = Py_NewRef(watchdog_expired);
    core->halted = Py_NewRef(halted);
    core->min_tolerance_ns = min_tolerance_ns;
    if (offsets_of(core->system_type, SYSTEM_NAMES, core->sys_off) < 0 ||
        offsets_of(core->stats_type, STATS_NAMES, core->stats_off) < 0 ||
        offsets_of(core->program_type, PROGRAM_NAMES, core->prog_off) < 0 ||
        offsets_of(core->pstats_type, PSTATS_NAMES, core->pstats_off) < 0 ||
        offsets_of(core->table_type, TABLE_NAMES, core->table_off) < 0 ||
        offsets_of(Py_TYPE(resource), RESOURCE_NAMES, core->res_off) < 0 ||
        offsets_of(Py_TYPE(variables), VARIABLES_NAMES, core->var_off) < 0 ||
        offsets_of(Py_TYPE(forcing), FORCING_NAMES, core->forcing_off) < 0 ||
        offsets_of(Py_TYPE(debugger), DEBUGGER_NAMES, core->debugger_off) < 0 ||
        offsets_of(Py_TYPE(scheduler), SCHEDULER_NAMES, core->scheduler_off) < 0 ||
        offsets_of(Py_TYPE(watchdog), WATCHDOG_NAMES, core->watchdog_off) < 0 ||
        offsets_of(Py_TYPE(io), IO_NAMES, core->io_off) < 0) {
        Py_DECREF(core);
        return NULL;
    }
    if (!Py_IS_TYPE(system, core->system_type)) {
        PyErr_SetString(PyExc_TypeError, "Core(): the system is no SystemView");
        Py_DECREF(core);
        return NULL;
    }
    return (PyObject *)core;
}

#define CORE_OBJECTS(V)                                                                     \
    V(resource) V(clock) V(io) V(forcing) V(debugger) V(variables) V(scheduler) V(watchdog)  \
    V(system) V(deadlines) V(running1) V(running2) V(program_run) V(direct) V(copy_globals) \
    V(watchdog_expired) V(halted)

static int Core_traverse(Core *core, visitproc visit, void *arg) {
#define VISIT(name) Py_VISIT(core->name);
    CORE_OBJECTS(VISIT)
#undef VISIT
    Py_VISIT(core->system_type);
    Py_VISIT(core->stats_type);
    Py_VISIT(core->program_type);
    Py_VISIT(core->pstats_type);
    Py_VISIT(core->table_type);
    return 0;
}

static int Core_clear(Core *core) {
#define CLEAR(name) Py_CLEAR(core->name);
    CORE_OBJECTS(CLEAR)
#undef CLEAR
    Py_CLEAR(core->system_type);
    Py_CLEAR(core->stats_type);
    Py_CLEAR(core->program_type);
    Py_CLEAR(core->pstats_type);
    Py_CLEAR(core->table_type);
    return 0;
}

static void Core_dealloc(Core *core) {
    PyObject_GC_UnTrack(core);
    Core_clear(core);
    Py_TYPE(core)->tp_free((PyObject *)core);
}

static PyObject *Core_cycle_checked(Core *core, PyObject *unused) {
    if (core->resource == NULL) { /* cleared by the cycle collector */
        PyErr_SetString(PyExc_RuntimeError, "the cycle core was cleared");
        return NULL;
    }
    return Core_cycle(core, unused);
}

static PyMethodDef Core_methods[] = {
    {"cycle", (PyCFunction)Core_cycle_checked, METH_NOARGS,
     "The usual CPU cycle: True once run, False when the Python cycle must run it."},
    {NULL, NULL, 0, NULL},
};

static PyTypeObject CoreType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "padt_cycle.Core",
    .tp_basicsize = sizeof(Core),
    .tp_flags = Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC,
    .tp_new = Core_new,
    .tp_dealloc = (destructor)Core_dealloc,
    .tp_traverse = (traverseproc)Core_traverse,
    .tp_clear = (inquiry)Core_clear,
    .tp_methods = Core_methods,
    .tp_doc = "The usual CPU cycle of one resource, in C.",
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, .m_name = "padt_cycle", .m_size = -1,
};

PyMODINIT_FUNC PADT_INIT(void) {
    if (PyType_Ready(&CoreType) < 0)
        return NULL;
    PyObject *made = PyModule_Create(&module);
    if (made == NULL)
        return NULL;
    if (PyModule_AddObjectRef(made, "Core", (PyObject *)&CoreType) < 0) {
        Py_DECREF(made);
        return NULL;
    }
    return made;
}

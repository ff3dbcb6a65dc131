/* Quaternions of the rotations nearest to 3x3 blocks, one block at a time with the GIL released:
 * the compiled form of lorisnb.core.trajectory.rotations._rotation_run (see its docstrings for the method).
 *
 * Every value is computed with the same IEEE double operations in the same order as the numpy
 * code (no fused multiply-add: built with -ffp-contract=off), so both give the same bits; the
 * tests compare them on real files and on random, perturbed, huge and non-finite blocks. The
 * numpy code stays the reference and the fallback where this module was not built. */

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#define STEPS_MAX 12

/* np.maximum: NaN if either is NaN, else the larger */
static inline double nan_max(double a, double b) {
    if (isnan(a)) return a;
    if (isnan(b)) return b;
    return a >= b ? a : b;
}

/* matrices._first_largest: 0, 1 or 2 where a, b, c is the first largest of a, b, c, d; else 3 */
static inline int first_largest(double a, double b, double c, double d) {
    if (a >= b && a >= c && a >= d) return 0;
    if (b >= c && b >= d) return 1;
    if (c >= d) return 2;
    return 3;
}

/* matrices.power_steps of one block */
static inline int power_steps(double off, const double *thresholds) {
    if (!(off > 0.0 && off < 0.25)) return STEPS_MAX;
    int steps = 0;
    while (steps < STEPS_MAX && thresholds[steps] <= off) steps++; /* searchsorted, side="right" */
    return steps < 1 ? 1 : steps;
}

static void nearest_run(const double *const e[9], const double *thresholds, Py_ssize_t n, double *q, double *off) {
    for (Py_ssize_t r = 0; r < n; r++) {
        const double a00 = e[0][r], a01 = e[1][r], a02 = e[2][r];
        const double a10 = e[3][r], a11 = e[4][r], a12 = e[5][r];
        const double a20 = e[6][r], a21 = e[7][r], a22 = e[8][r];
        const double a[3][3] = {{a00, a01, a02}, {a10, a11, a12}, {a20, a21, a22}};
        /* Bar-Itzhack's K + I, written as BarItzhack._build writes it */
        const double tr = (a00 + a11) + a22;
        const double one_minus = 1.0 - tr;
        const double xx = one_minus + a00 * 2.0, yy = one_minus + a11 * 2.0, zz = one_minus + a22 * 2.0;
        const double ww = tr + 1.0;
        const double xy = a10 + a01, xz = a20 + a02, yz = a21 + a12;
        const double xw = a21 - a12, yw = a02 - a20, zw = a10 - a01;
        /* the largest entry of |R R^T - I|, then the distance with |det R - 1| */
        static const int pairs[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
        double gram = 0.0;
        for (int p = 0; p < 6; p++) {
            const int i = pairs[p][0], j = pairs[p][1];
            double d = a[i][0] * a[j][0];
            d = d + a[i][1] * a[j][1];
            d = d + a[i][2] * a[j][2];
            if (i == j) d = d - 1.0;
            d = fabs(d);
            gram = p == 0 ? d : nan_max(gram, d);
        }
        const int orthogonal = gram <= 1e-12;
        double det = a00 * (a11 * a22 - a12 * a21);
        det = det - a01 * (a10 * a22 - a12 * a20);
        det = det + a02 * (a10 * a21 - a11 * a20);
        const double distance = nan_max(gram, fabs(det - 1.0));
        off[r] = distance;
        /* Markley's quaternion: the column of K + I of the first largest of the diagonal and trace */
        const double col[4][4] = {{xx, xy, xz, xw}, {xy, yy, yz, yw}, {xz, yz, zz, zw}, {xw, yw, zw, ww}};
        const int branch = first_largest(a00, a11, a22, tr);
        double x = col[branch][0], y = col[branch][1], z = col[branch][2], w = col[branch][3];
        if (!orthogonal) {
            /* power steps on K + I, then the largest component made positive */
            const int steps = power_steps(distance, thresholds);
            for (int s = 0; s < steps; s++) {
                double v[4];
                for (int i = 0; i < 4; i++) {
                    double o = col[i][0] * x;
                    o = o + col[i][1] * y;
                    o = o + col[i][2] * z;
                    o = o + col[i][3] * w;
                    v[i] = o;
                }
                x = v[0], y = v[1], z = v[2], w = v[3];
            }
            const int largest = first_largest(fabs(x), fabs(y), fabs(z), fabs(w));
            const double sign_of = largest == 0 ? x : largest == 1 ? y : largest == 2 ? z : w;
            if (sign_of < 0.0) x = -x, y = -y, z = -z, w = -w;
        }
        double norm = x * x;
        norm = norm + y * y;
        norm = norm + z * z;
        norm = norm + w * w;
        norm = sqrt(norm);
        q[4 * r] = x / norm;
        q[4 * r + 1] = y / norm;
        q[4 * r + 2] = z / norm;
        q[4 * r + 3] = w / norm;
    }
}

/* a C-contiguous float64 buffer of `count` doubles (-1: any count, returned in *count) */
static int double_buffer(PyObject *obj, Py_buffer *view, int writable, Py_ssize_t *count, const char *what) {
    if (PyObject_GetBuffer(obj, view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0)) < 0)
        return -1;
    if (view->itemsize != 8 || view->format == NULL || strcmp(view->format, "d") != 0 ||
        (*count >= 0 && view->len != *count * 8)) {
        PyErr_Format(PyExc_ValueError, "%s: expected %zd contiguous float64 values", what, *count);
        PyBuffer_Release(view);
        return -1;
    }
    *count = view->len / 8;
    return 0;
}

static PyObject *nearest(PyObject *self, PyObject *args) {
    PyObject *entries, *thresholds_obj, *q_obj, *off_obj;
    if (!PyArg_ParseTuple(args, "OOOO", &entries, &thresholds_obj, &q_obj, &off_obj)) return NULL;
    PyObject *seq = PySequence_Fast(entries, "entries: expected a sequence of 9 arrays");
    if (seq == NULL) return NULL;
    if (PySequence_Fast_GET_SIZE(seq) != 9) {
        Py_DECREF(seq);
        PyErr_SetString(PyExc_ValueError, "entries: expected 9 arrays (B_00, B_01, ..., B_22)");
        return NULL;
    }
    Py_buffer views[12];
    int held = 0;
    Py_ssize_t n = -1, twelve = STEPS_MAX;
    PyObject *result = NULL;
    for (; held < 9; held++) {
        if (double_buffer(PySequence_Fast_GET_ITEM(seq, held), &views[held], 0, &n, "entries") < 0) goto done;
    }
    if (double_buffer(thresholds_obj, &views[held], 0, &twelve, "thresholds") < 0) goto done;
    held++;
    Py_ssize_t four_n = 4 * n;
    if (double_buffer(q_obj, &views[held], 1, &four_n, "q") < 0) goto done;
    held++;
    if (double_buffer(off_obj, &views[held], 1, &n, "off") < 0) goto done;
    held++;
    {
        const double *e[9];
        for (int i = 0; i < 9; i++) e[i] = (const double *)views[i].buf;
        const double *thresholds = (const double *)views[9].buf;
        double *q = (double *)views[10].buf, *off = (double *)views[11].buf;
        Py_BEGIN_ALLOW_THREADS nearest_run(e, thresholds, n, q, off);
        Py_END_ALLOW_THREADS
    }
    result = Py_NewRef(Py_None);
done:
    for (int i = 0; i < held; i++) PyBuffer_Release(&views[i]);
    Py_DECREF(seq);
    return result;
}

static PyMethodDef methods[] = {
    {"nearest", nearest, METH_VARARGS,
     "nearest(entries, thresholds, q, off): quaternions xyzw of the rotations nearest to n blocks into q "
     "(4n doubles) and their distance from a rotation into off (n), as matrices._rotation_run; entries: "
     "the 9 contiguous float64 (n,) arrays B_00, B_01, ..., B_22; thresholds: matrices._STEP_THRESHOLDS."},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_rotations", NULL, -1, methods};

PyMODINIT_FUNC PyInit__rotations(void) { return PyModule_Create(&module); }

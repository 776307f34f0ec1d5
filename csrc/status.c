/* status.c -- messages for the status codes of mcgeom.h. */
#include "mcgeom.h"

const char *mcg_status_message(int status)
{
    switch (status) {
    case MCG_OK: return "ok";
    case MCG_EINVAL: return "invalid argument (size, NULL pointer, NaN or inf)";
    case MCG_ENUMERIC: return "numerical failure (no convergence or singular system)";
    case MCG_ENOMEM: return "workspace too small";
    case MCG_EINFEASIBLE: return "problem is infeasible";
    case MCG_EDEGENERATE: return "degenerate data or motion for this method";
    case MCG_EUNAVAILABLE: return "optional component not available (GLPK backend not built or libglpk not loaded)";
    default: return "unknown status code";
    }
}

/* Fault injection for tests: a named point of the code that can be made to
 * fail on purpose, to test the paths that handle failures no test could
 * cause otherwise (an allocation failing on one rank of a job, say).
 *
 * Honoured only in builds with the test suite (TB_TESTS, which defines
 * TB_FAULT_INJECTION); elsewhere tb_fault() is always false. The
 * environment variable TB_FAULT lists the points to fail, separated by
 * commas: `POINT[@RANK][:N]` fails POINT from its N-th pass on (default 1),
 * in the process of MPI rank RANK only (from OMPI_COMM_WORLD_RANK or
 * PMIX_RANK; default every process).
 *
 *     if (!buf || tb_fault("tile-merge")) ... the failure path ...
 */
#ifndef TB_UTIL_BASE_FAULT_H
#define TB_UTIL_BASE_FAULT_H

#include <stdbool.h>

/* True if the test environment asks `point` to fail now (counts the pass). */
bool tb_fault(const char *point);

#endif

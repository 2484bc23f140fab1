#include <freeinit/report/version.h>

namespace freeinit::report {

const char* version() { return FREEINIT_VERSION; }

}  // namespace freeinit::report

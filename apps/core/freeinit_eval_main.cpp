// freeinit-eval: Free-Init and the baseline initializers on simulated scenarios, against the
// ground truth and the Cramer-Rao bound of each run (freeinit/report/eval_app.h).
#include <freeinit/report/eval_app.h>

int main(int argc, char** argv) { return freeinit::report::EvalApp::main(argc, argv); }

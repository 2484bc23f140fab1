// freeinit-eval: Free-Init and the baseline initializers on simulated scenarios, against the
// ground truth and the Cramer-Rao bound of each run (EvalApp, eval_app.h).
#include "eval_app.h"

int main(int argc, char** argv) { return freeinit::apps::EvalApp::main(argc, argv); }

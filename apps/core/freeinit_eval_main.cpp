// freeinit-eval: Free-Init and the baseline initializers on simulated scenarios, against the
// ground truth and the Cramer-Rao bound of each run (freeinit/report/eval_app.h).
#include <freeinit/report/eval_app.h>
#include <freeinit/report/version.h>

#include <exception>
#include <iostream>

int main(int argc, char** argv) {
  using freeinit::report::EvalApp;
  EvalApp app;
  try {
    switch (app.parse(argc, argv)) {
      case EvalApp::Action::Help:
        std::cout << EvalApp::usage();
        return 0;
      case EvalApp::Action::Version:
        std::cout << "freeinit-eval " << freeinit::report::version() << "\n";
        return 0;
      case EvalApp::Action::Run:
        break;
    }
  } catch (const EvalApp::UsageError& e) {
    std::cerr << "freeinit-eval: " << e.what() << "\n";
    return 2;
  }
  try {
    app.run(std::cout, std::cerr);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "freeinit-eval: " << e.what() << "\n";
    return 1;
  }
}

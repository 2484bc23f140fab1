// Numbers as text, in the three forms the project prints them: the shortest exact text (the INI
// files' values), a number of significant digits (messages) and a number of decimals (logs and
// tables). Standard library only; every layer, the core included, uses them.
#pragma once

#include <string>

namespace freeinit {

/// The shortest text that reads back as exactly x (std::to_chars), e.g. 0.1 -> "0.1".
std::string formatNumber(double x);

/// x with `digits` significant digits as a stream prints it by default (printf's %.<digits>g),
/// e.g. (0.012345, 3) -> "0.0123", (1234567, 3) -> "1.23e+06".
std::string formatSignificant(double x, int digits);

/// x with `decimals` digits after the point (std::fixed), e.g. (1.5, 3) -> "1.500".
std::string formatFixed(double x, int decimals);

}  // namespace freeinit

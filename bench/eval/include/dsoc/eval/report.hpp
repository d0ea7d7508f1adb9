#pragma once
// dsoc-eval's output: a Markdown table for people, a JSON document for tools.

#include "dsoc/eval/evaluation.hpp"

#include <iosfwd>
#include <string>

namespace dsoc::eval {

/// The Markdown report: a header naming the run, the table (one row per policy plus
/// the oracle's ideal), TBV figures and any violation examples.
void write_markdown(const EvalResult& result, const std::string& command, std::ostream& out);

/// Every figure of the run as JSON (keys documented in docs/evaluation.md).
[[nodiscard]] std::string to_json(const EvalResult& result, const std::string& command);

} // namespace dsoc::eval

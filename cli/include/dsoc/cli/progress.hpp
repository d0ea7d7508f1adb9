#pragma once
// A long job's progress on stderr (a bake): on a terminal one line rewritten in place,
// elsewhere (a log file, a pipe, a service manager's journal) a line of its own at
// every tenth of the work, so that logs stay readable.

#include <cstdio>
#include <string>

namespace dsoc::cli {

class ProgressLine {
public:
    /// Writes to stderr, rewriting in place when stderr is a terminal. `what` names
    /// the job, e.g. "baking the cell visibility of oa_dm4".
    explicit ProgressLine(std::string what);
    /// Writes to `out`; `terminal` chooses the in-place form.
    ProgressLine(std::string what, std::FILE* out, bool terminal);

    /// `fraction` of the work done (0..1) after `elapsed_seconds`; the line ends at 1.
    void operator()(double fraction, double elapsed_seconds);
    /// The work starts over (another try at it): ends a line rewritten in place, so
    /// that a message may follow on a line of its own, and reports from 0 again.
    void restart();

private:
    std::string what_;
    std::FILE* out_;
    bool terminal_;
    int last_tenth_ = -1;  ///< the last tenth written (not on a terminal)
    bool written_ = false; ///< a line is open on the terminal
};

} // namespace dsoc::cli

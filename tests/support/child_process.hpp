#pragma once
// Runs a built program as a child process for end-to-end tests of the programs: its
// exit status, stdout and stderr, under a time limit. stdout and stderr go to files in
// a temporary directory (no pipe to fill and block the child), read as they grow.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace dsoc::testing {

/// A started program. The environment is the test's, without DSOC_CONFIG (a
/// developer's shell must not change what the tests see), plus `environment`
/// ("NAME=value" each). Killed with SIGKILL if still running when destroyed.
class ChildProcess {
public:
    ChildProcess(const std::vector<std::string>& argv,
                 const std::vector<std::string>& environment = {}) {
        char dir_template[] = "/tmp/dsoc-child-XXXXXX";
        if (::mkdtemp(dir_template) == nullptr) {
            throw std::runtime_error("mkdtemp failed");
        }
        dir_ = dir_template;
        out_path_ = dir_ / "stdout";
        err_path_ = dir_ / "stderr";

        std::vector<std::string> env;
        for (char** e = environ; *e != nullptr; ++e) {
            if (std::string(*e).rfind("DSOC_CONFIG=", 0) != 0) {
                env.emplace_back(*e);
            }
        }
        env.insert(env.end(), environment.begin(), environment.end());
        std::vector<char*> args;
        for (const auto& a : argv) {
            args.push_back(const_cast<char*>(a.c_str()));
        }
        args.push_back(nullptr);
        std::vector<char*> envp;
        for (auto& e : env) {
            envp.push_back(e.data());
        }
        envp.push_back(nullptr);

        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
        posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_path_.c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC, 0600);
        posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path_.c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC, 0600);
        const int error = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), envp.data());
        posix_spawn_file_actions_destroy(&actions);
        if (error != 0) {
            throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(error));
        }
    }
    ~ChildProcess() {
        if (running()) {
            ::kill(pid_, SIGKILL);
            int status = 0;
            ::waitpid(pid_, &status, 0);
        }
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    [[nodiscard]] bool running() const { return status_ == kRunning; }

    void signal(int number) const {
        if (running()) {
            ::kill(pid_, number);
        }
    }

    /// Waits until the child exits, at most `timeout` (then kills it). Returns its exit
    /// status, or 128 + the signal that ended it, as a shell reports it.
    int wait(std::chrono::duration<double> timeout = std::chrono::seconds(60)) {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (running()) {
            int status = 0;
            const pid_t done = ::waitpid(pid_, &status, WNOHANG);
            if (done == pid_) {
                status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            } else if (std::chrono::steady_clock::now() > deadline) {
                ::kill(pid_, SIGKILL);
            } else {
                std::this_thread::sleep_for(std::chrono::milliseconds(10));
            }
        }
        return status_;
    }

    /// What the child wrote so far.
    [[nodiscard]] std::string out() const { return read(out_path_); }
    [[nodiscard]] std::string err() const { return read(err_path_); }

    /// Waits until stdout holds `text` (returns true) or the child exits or `timeout`
    /// passes (false).
    bool wait_for_output(const std::string& text,
                         std::chrono::duration<double> timeout = std::chrono::seconds(30)) {
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < deadline) {
            if (out().find(text) != std::string::npos) {
                return true;
            }
            int status = 0;
            if (running() && ::waitpid(pid_, &status, WNOHANG) == pid_) {
                status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
                return out().find(text) != std::string::npos;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        return false;
    }

private:
    static constexpr int kRunning = -1;

    static std::string read(const std::filesystem::path& path) {
        std::ifstream in(path, std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        return text.str();
    }

    std::filesystem::path dir_;
    std::filesystem::path out_path_;
    std::filesystem::path err_path_;
    pid_t pid_ = -1;
    int status_ = kRunning;
};

/// A finished run of a program.
struct ProgramRun {
    int status = -1;
    std::string out;
    std::string err;
};

/// Runs `argv` to its end (at most `timeout`).
inline ProgramRun run_program(const std::vector<std::string>& argv,
                              const std::vector<std::string>& environment = {},
                              std::chrono::duration<double> timeout = std::chrono::seconds(60)) {
    ChildProcess child(argv, environment);
    ProgramRun run;
    run.status = child.wait(timeout);
    run.out = child.out();
    run.err = child.err();
    return run;
}

} // namespace dsoc::testing

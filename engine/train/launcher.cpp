// Rank processes: fork/exec, output forwarding through pipes and poll, failure propagation.
#include "engine/train/launcher.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "engine/core/error.h"

extern char** environ;

namespace dynscope {

namespace {

std::atomic<int> g_forward_signal{0};

void on_signal(int sig) { g_forward_signal = sig; }

// One rank's process and its two output pipes (stdout, stderr) with partial lines.
struct Child {
  int rank = 0;
  pid_t pid = -1;
  int fd[2] = {-1, -1};
  std::string pending[2];
  bool running = true;
  RankExit exit;
};

void write_all(int fd, const std::string& text) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<size_t>(n);
  }
}

// Forwards complete lines (ended by \n or \r) of `c`'s stream `s` with the rank prefix.
void forward(Child& c, int s, bool flush) {
  std::string& buf = c.pending[s];
  const std::string prefix = "[rank " + std::to_string(c.rank) + "] ";
  size_t start = 0;
  for (size_t i = 0; i < buf.size(); ++i) {
    if (buf[i] != '\n' && buf[i] != '\r') continue;
    if (i > start) write_all(s == 0 ? 1 : 2, prefix + buf.substr(start, i - start) + "\n");
    start = i + 1;
  }
  buf.erase(0, start);
  if (flush && !buf.empty()) {
    write_all(s == 0 ? 1 : 2, prefix + buf + "\n");
    buf.clear();
  }
}

void drain(Child& c, int s) {
  char chunk[4096];
  while (c.fd[s] >= 0) {
    const ssize_t n = ::read(c.fd[s], chunk, sizeof chunk);
    if (n > 0) {
      c.pending[s].append(chunk, static_cast<size_t>(n));
      forward(c, s, false);
      continue;
    }
    if (n < 0 && (errno == EINTR)) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    forward(c, s, true);  // EOF or error: the stream is done
    ::close(c.fd[s]);
    c.fd[s] = -1;
  }
}

std::string describe(const RankExit& e) {
  std::string who = "rank " + std::to_string(e.rank) + " (pid " + std::to_string(e.pid) + ")";
  if (e.signal != 0) {
    return who + " was killed by signal " + std::to_string(e.signal) + " (" + strsignal(e.signal) +
           ")";
  }
  return who + " exited with status " + std::to_string(e.code);
}

}  // namespace

void LaunchOptions::validate() const {
  if (executable.empty()) throw ValueError("executable", "no program to launch");
  if (nproc < 1 || nproc > 1024) throw ValueError("--nproc", "must be in [1, 1024]");
  if (nnodes < 1 || nnodes > 65536) throw ValueError("--nnodes", "must be in [1, 65536]");
  if (node_rank < 0 || node_rank >= nnodes) {
    throw ValueError("--node-rank",
                     std::to_string(node_rank) + " is outside [0, " + std::to_string(nnodes) + ")");
  }
  if (master_port < 0 || master_port > 65535) {
    throw ValueError("--master-port", "must be in [1, 65535]");
  }
  if (nnodes > 1 && master_port == 0) {
    throw ValueError("--master-port", "a job of several machines needs an agreed port");
  }
  if (master_addr.empty()) throw ValueError("--master-addr", "is empty");
}

std::string LaunchResult::failure() const {
  for (const RankExit& e : ranks) {
    if (e.rank == failed_rank) return describe(e);
  }
  return "";
}

int free_local_port() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) throw Error(std::string("cannot open a socket: ") + std::strerror(errno));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(s, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    const std::string why = std::strerror(errno);
    ::close(s);
    throw Error("cannot find a free port: " + why);
  }
  ::close(s);
  return ntohs(addr.sin_port);
}

LaunchResult launch_ranks(const LaunchOptions& given) {
  given.validate();
  LaunchOptions o = given;
  if (o.master_port == 0) o.master_port = free_local_port();
  const int world = o.nproc * o.nnodes;
  std::fflush(stdout);
  std::fflush(stderr);

  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  struct sigaction old_int {
  }, old_term{};
  g_forward_signal = 0;
  sigaction(SIGINT, &action, &old_int);
  sigaction(SIGTERM, &action, &old_term);

  std::vector<Child> children(static_cast<size_t>(o.nproc));
  // Each rank leads a process group of its own, so a signal reaches what it started too.
  auto stop_all = [&](int sig) {
    for (Child& c : children) {
      if (c.running && c.pid > 0) ::kill(-c.pid, sig);
    }
  };
  for (int i = 0; i < o.nproc; ++i) {
    Child& c = children[static_cast<size_t>(i)];
    c.rank = o.node_rank * o.nproc + i;
    int out[2], err[2];
    if (::pipe(out) != 0 || ::pipe(err) != 0) {
      stop_all(SIGKILL);
      throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
    }
    std::vector<std::string> env = {
        "RANK=" + std::to_string(c.rank),  "WORLD_SIZE=" + std::to_string(world),
        "LOCAL_RANK=" + std::to_string(i), "LOCAL_WORLD_SIZE=" + std::to_string(o.nproc),
        "MASTER_ADDR=" + o.master_addr,    "MASTER_PORT=" + std::to_string(o.master_port)};
    env.insert(env.end(), o.env.begin(), o.env.end());
    // This process's environment minus the names set here, then ours. Everything the child
    // needs is built before fork(): after it, only system calls (no allocation) run there.
    std::vector<std::string> environment;
    for (char** e = environ; e && *e; ++e) {
      const std::string entry = *e;
      const std::string name = entry.substr(0, entry.find('='));
      const bool replaced = std::any_of(env.begin(), env.end(), [&](const std::string& v) {
        return v.compare(0, name.size() + 1, name + "=") == 0;
      });
      if (!replaced) environment.push_back(entry);
    }
    environment.insert(environment.end(), env.begin(), env.end());
    std::vector<char*> cenv;
    for (std::string& e : environment) cenv.push_back(e.data());
    cenv.push_back(nullptr);
    std::vector<std::string> argv = {o.executable};
    argv.insert(argv.end(), o.args.begin(), o.args.end());
    std::vector<char*> cargv;
    for (std::string& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    static const char kExecFailed[] = "launcher: cannot run the rank's program\n";
    const pid_t pid = ::fork();
    if (pid < 0) {
      stop_all(SIGKILL);
      throw Error(std::string("cannot start rank ") + std::to_string(c.rank) + ": " +
                  std::strerror(errno));
    }
    if (pid == 0) {
      ::setpgid(0, 0);
      ::dup2(out[1], 1);
      ::dup2(err[1], 2);
      ::close(out[0]);
      ::close(out[1]);
      ::close(err[0]);
      ::close(err[1]);
      ::execve(o.executable.c_str(), cargv.data(), cenv.data());
      [[maybe_unused]] const ssize_t n = ::write(2, kExecFailed, sizeof kExecFailed - 1);
      ::_exit(127);
    }
    ::setpgid(pid, pid);  // also here: no race with the first signal
    ::close(out[1]);
    ::close(err[1]);
    c.pid = pid;
    c.fd[0] = out[0];
    c.fd[1] = err[0];
    for (int fd : c.fd) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
    c.exit.rank = c.rank;
    c.exit.pid = pid;
    std::fprintf(stderr, "started rank %d (pid %d) of %d\n", c.rank, static_cast<int>(pid), world);
  }
  std::fflush(stderr);

  LaunchResult result;
  std::chrono::steady_clock::time_point kill_at{};
  bool stopping = false;
  int running = o.nproc;
  // Output is read while any rank runs; after the last one ends, what is left in the pipes is
  // read once (a process a rank left behind may hold them open).
  for (bool last = false; !last;) {
    last = running == 0;
    std::vector<pollfd> fds;
    std::vector<std::pair<size_t, int>> who;
    for (size_t i = 0; i < children.size(); ++i) {
      for (int s = 0; s < 2; ++s) {
        if (children[i].fd[s] < 0) continue;
        fds.push_back({children[i].fd[s], POLLIN, 0});
        who.emplace_back(i, s);
      }
    }
    if (!fds.empty()) {
      const int n = ::poll(fds.data(), fds.size(), last ? 0 : 100);
      if (n > 0) {
        for (size_t k = 0; k < fds.size(); ++k) {
          if (fds[k].revents != 0) drain(children[who[k].first], who[k].second);
        }
      }
    } else {
      ::usleep(20000);
    }
    if (const int sig = g_forward_signal.exchange(0)) {
      std::fprintf(stderr, "launcher: passing signal %d to the ranks\n", sig);
      stop_all(sig);
      if (!stopping) {
        stopping = true;
        kill_at = std::chrono::steady_clock::now() + o.grace;
      }
    }
    // Ranks that ended since the last look; one killed by a signal is the likelier cause of the
    // others' failures (they lose their peer), so it is named first.
    std::vector<Child*> ended;
    for (Child& c : children) {
      if (!c.running) continue;
      int status = 0;
      if (::waitpid(c.pid, &status, WNOHANG) != c.pid) continue;
      c.running = false;
      --running;
      if (WIFSIGNALED(status)) {
        c.exit.signal = WTERMSIG(status);
        c.exit.code = 128 + c.exit.signal;
      } else {
        c.exit.code = WEXITSTATUS(status);
      }
      ended.push_back(&c);
    }
    std::stable_sort(ended.begin(), ended.end(), [](const Child* a, const Child* b) {
      return (a->exit.signal != 0) > (b->exit.signal != 0);
    });
    for (Child* c : ended) {
      c->exit.stopped_by_launcher = stopping && result.failed_rank >= 0;
      if (c->exit.code != 0 && result.failed_rank < 0) {
        result.failed_rank = c->rank;
        std::fprintf(stderr, "launcher: %s; stopping the other ranks\n", describe(c->exit).c_str());
        std::fflush(stderr);
        stop_all(SIGTERM);
        stopping = true;
        kill_at = std::chrono::steady_clock::now() + o.grace;
      }
    }
    if (stopping && running > 0 && std::chrono::steady_clock::now() >= kill_at) {
      stop_all(SIGKILL);
      kill_at = std::chrono::steady_clock::now() + std::chrono::hours(1);
    }
  }
  for (Child& c : children) {
    for (int s = 0; s < 2; ++s) {
      if (c.fd[s] < 0) continue;
      forward(c, s, true);
      ::close(c.fd[s]);
      c.fd[s] = -1;
    }
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  for (const Child& c : children) result.ranks.push_back(c.exit);
  if (result.failed_rank < 0) {
    for (const RankExit& e : result.ranks) {
      if (e.code != 0) {
        result.failed_rank = e.rank;
        break;
      }
    }
  }
  return result;
}

}  // namespace dynscope

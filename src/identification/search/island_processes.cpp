#include "motion_model_estimation/identification/search/island_processes.h"

#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <type_traits>

namespace mme {
namespace {

// One frame on a socket: its length (uint64) then its bytes; the first byte names the request or
// reply. Numbers travel as their bytes (both ends are the same program on the same host), so
// doubles arrive bit for bit.
enum Kind : uint8_t {
  kStep = 1,     // -> kReport
  kEmigrants,    // int32 count -> kIndividuals
  kImmigrate,    // individuals -> kImmigrated (int32 entered, report)
  kStop,         // no reply; the child exits
  kReport,
  kIndividuals,
  kImmigrated,
  kError,        // string: the child failed and exits
};

class Writer {
 public:
  template <typename T>
  void put(T value) {
    static_assert(std::is_trivially_copyable<T>::value, "raw bytes only");
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void putDoubles(const std::vector<double>& values) {
    put<uint64_t>(values.size());
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
  }
  void putString(const std::string& text) {
    put<uint64_t>(text.size());
    bytes_ += text;
  }
  void putIndividual(const Individual& ind) {
    putDoubles(ind.genes);
    putDoubles(ind.mutability);
    putDoubles(ind.local_costs);
    put(ind.cost);
  }
  void putIndividuals(const std::vector<Individual>& individuals) {
    put<uint64_t>(individuals.size());
    for (const Individual& ind : individuals) putIndividual(ind);
  }
  void putReport(const EvolutionStrategy& es) {
    put<int32_t>(es.generation());
    put<uint64_t>(es.evaluations());
    put<int32_t>(es.refinements());
    put<int32_t>(static_cast<int32_t>(es.lastRefineStatus()));
    putIndividual(es.best());
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class Reader {
 public:
  explicit Reader(const std::string& bytes) : bytes_(bytes) {}
  template <typename T>
  T get() {
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  std::vector<double> getDoubles() {
    const uint64_t n = get<uint64_t>();
    if (n > bytes_.size() / sizeof(double)) throw std::runtime_error("island message: bad length");
    std::vector<double> values(n);
    if (n > 0) std::memcpy(values.data(), take(n * sizeof(double)), n * sizeof(double));
    return values;
  }
  std::string getString() {
    const uint64_t n = get<uint64_t>();
    if (n > bytes_.size()) throw std::runtime_error("island message: bad length");
    return std::string(take(n), n);
  }
  Individual getIndividual() {
    Individual ind;
    ind.genes = getDoubles();
    ind.mutability = getDoubles();
    ind.local_costs = getDoubles();
    ind.cost = get<double>();
    return ind;
  }
  std::vector<Individual> getIndividuals() {
    const uint64_t n = get<uint64_t>();
    if (n > bytes_.size()) throw std::runtime_error("island message: bad length");
    std::vector<Individual> out;
    for (uint64_t i = 0; i < n; ++i) out.push_back(getIndividual());
    return out;
  }
  IslandReport getReport() {
    IslandReport r;
    r.generation = get<int32_t>();
    r.evaluations = get<uint64_t>();
    r.refinements = get<int32_t>();
    r.last_refine_status = static_cast<RefineStatus>(get<int32_t>());
    r.best = getIndividual();
    return r;
  }

 private:
  const char* take(size_t n) {
    if (n > bytes_.size() - pos_) throw std::runtime_error("island message: truncated");
    const char* at = bytes_.data() + pos_;
    pos_ += n;
    return at;
  }
  const std::string& bytes_;
  size_t pos_ = 0;
};

/// Writes all of `size` bytes; false when the other end has gone (no SIGPIPE).
bool sendBytes(int fd, const char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::send(fd, data, size, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

/// Reads exactly `size` bytes; false at end of stream or on an error.
bool receiveBytes(int fd, char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::read(fd, data, size);
    if (n < 0 && errno == EINTR) continue;  // a signal (e.g. identify's SIGINT handler)
    if (n <= 0) return false;
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

bool sendFrame(int fd, const std::string& payload) {
  const uint64_t size = payload.size();
  return sendBytes(fd, reinterpret_cast<const char*>(&size), sizeof(size)) &&
         sendBytes(fd, payload.data(), payload.size());
}

bool receiveFrame(int fd, std::string* payload) {
  uint64_t size = 0;
  if (!receiveBytes(fd, reinterpret_cast<char*>(&size), sizeof(size))) return false;
  if (size > (uint64_t{1} << 34)) return false;  // not a frame of ours
  payload->resize(size);
  return receiveBytes(fd, &(*payload)[0], size);
}

/// The answer of a child to one request.
std::string serveRequest(EvolutionStrategy& es, const std::string& request, bool die_at_second) {
  Reader in(request);
  Writer out;
  switch (in.get<uint8_t>()) {
    case kStep:
      if (die_at_second && es.generation() == 1) ::raise(SIGKILL);
      es.step();
      out.put<uint8_t>(kReport);
      out.putReport(es);
      break;
    case kEmigrants:
      out.put<uint8_t>(kIndividuals);
      out.putIndividuals(es.emigrants(in.get<int32_t>()));
      break;
    case kImmigrate: {
      const int entered = es.immigrate(in.getIndividuals());
      out.put<uint8_t>(kImmigrated);
      out.put<int32_t>(entered);
      out.putReport(es);
      break;
    }
    default:
      throw std::runtime_error("unknown request");
  }
  return out.bytes();
}

/// A child's life: answer the parent's requests until it says stop or goes away, then exit
/// without running the parent's destructors or flushing its buffers (they are the parent's).
[[noreturn]] void serveIsland(EvolutionStrategy& es, int fd, bool die_at_second) {
  int code = 0;
  try {
    std::string request;
    while (receiveFrame(fd, &request)) {
      if (!request.empty() && static_cast<uint8_t>(request[0]) == kStop) break;
      if (!sendFrame(fd, serveRequest(es, request, die_at_second))) break;
    }
  } catch (const std::exception& e) {
    Writer out;
    out.put<uint8_t>(kError);
    out.putString(e.what());
    sendFrame(fd, out.bytes());
    code = 1;
  }
  ::_exit(code);
}

/// How a reaped child ended, in words.
std::string endedHow(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return "was killed by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")";
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "ended";
}

std::string request(Kind kind) {
  Writer w;
  w.put<uint8_t>(kind);
  return w.bytes();
}

}  // namespace

IslandProcesses::IslandProcesses(const std::vector<std::unique_ptr<EvolutionStrategy>>& islands) {
  const char* die = std::getenv(kTestDieVariable);
  const long die_island = die != nullptr && *die != '\0' ? std::strtol(die, nullptr, 10) : -1;
  std::fflush(nullptr);  // buffered output would otherwise be written again by every child
  for (size_t i = 0; i < islands.size(); ++i) {
    int pair[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0) {
      const std::string why = std::strerror(errno);
      failed_ = true;
      stopChildren();
      throw std::runtime_error("island " + std::to_string(i) + ": no socket for its process: " + why);
    }
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::close(pair[0]);
      for (const Child& c : children_) ::close(c.fd);  // the other islands' ends are not ours
      serveIsland(*islands[i], pair[1], static_cast<long>(i) == die_island);
    }
    ::close(pair[1]);
    if (pid < 0) {
      const std::string why = std::strerror(errno);
      ::close(pair[0]);
      failed_ = true;
      stopChildren();
      throw std::runtime_error("island " + std::to_string(i) + ": cannot start its process: " + why);
    }
    children_.push_back(Child{pid, pair[0]});
  }
}

IslandProcesses::~IslandProcesses() { stopChildren(); }

void IslandProcesses::stopChildren() {
  // A child answers every request before reading the next, so after a success each waits for a
  // request: stop tells it to exit, and a closed socket does too.
  for (Child& c : children_) {
    if (c.fd < 0) continue;
    if (!failed_) sendFrame(c.fd, request(kStop));
    ::close(c.fd);
    c.fd = -1;
  }
  for (Child& c : children_) {
    if (c.pid <= 0) continue;
    if (failed_) ::kill(c.pid, SIGKILL);  // it may be mid-generation: its work is not wanted
    while (::waitpid(c.pid, nullptr, 0) < 0 && errno == EINTR) {
    }
    c.pid = -1;
  }
  children_.clear();
}

void IslandProcesses::fail(size_t island, const std::string& what) {
  failed_ = true;
  throw std::runtime_error("island " + std::to_string(island) + " " + what);
}

void IslandProcesses::sendAll(const std::vector<std::string>& requests) {
  for (size_t i = 0; i < children_.size(); ++i)
    if (!sendFrame(children_[i].fd, requests[i])) receiveFrom(i);  // reports how it ended
}

std::string IslandProcesses::receiveFrom(size_t island) {
  Child& c = children_[island];
  std::string reply;
  if (!receiveFrame(c.fd, &reply)) {
    int status = 0;
    const pid_t pid = c.pid;
    pid_t got;
    while ((got = ::waitpid(c.pid, &status, 0)) < 0 && errno == EINTR) {
    }
    c.pid = -1;
    fail(island, "(process " + std::to_string(pid) + ") " + (got == pid ? endedHow(status) : "ended") +
                     " before answering the parent: the island model cannot go on without it");
  }
  if (!reply.empty() && static_cast<uint8_t>(reply[0]) == kError) {
    Reader in(reply);
    in.get<uint8_t>();
    fail(island, "(process " + std::to_string(c.pid) + ") failed: " + in.getString());
  }
  return reply;
}

std::vector<IslandReport> IslandProcesses::step() {
  sendAll(std::vector<std::string>(children_.size(), request(kStep)));
  std::vector<IslandReport> reports;
  for (size_t i = 0; i < children_.size(); ++i) {
    const std::string reply = receiveFrom(i);
    Reader in(reply);
    if (in.get<uint8_t>() != kReport) fail(i, "answered a generation with something else");
    reports.push_back(in.getReport());
  }
  return reports;
}

std::vector<std::vector<Individual>> IslandProcesses::emigrants(int count) {
  Writer w;
  w.put<uint8_t>(kEmigrants);
  w.put<int32_t>(count);
  sendAll(std::vector<std::string>(children_.size(), w.bytes()));
  std::vector<std::vector<Individual>> out;
  for (size_t i = 0; i < children_.size(); ++i) {
    const std::string reply = receiveFrom(i);
    Reader in(reply);
    if (in.get<uint8_t>() != kIndividuals) fail(i, "answered a request for emigrants with something else");
    out.push_back(in.getIndividuals());
  }
  return out;
}

std::vector<int> IslandProcesses::immigrate(const std::vector<std::vector<Individual>>& arrivals,
                                            std::vector<IslandReport>* reports) {
  std::vector<std::string> requests;
  for (const std::vector<Individual>& a : arrivals) {
    Writer w;
    w.put<uint8_t>(kImmigrate);
    w.putIndividuals(a);
    requests.push_back(w.bytes());
  }
  sendAll(requests);
  std::vector<int> entered(children_.size(), 0);
  reports->resize(children_.size());
  for (size_t i = 0; i < children_.size(); ++i) {
    const std::string reply = receiveFrom(i);
    Reader in(reply);
    if (in.get<uint8_t>() != kImmigrated) fail(i, "answered immigrants with something else");
    entered[i] = in.get<int32_t>();
    (*reports)[i] = in.getReport();
  }
  return entered;
}

}  // namespace mme

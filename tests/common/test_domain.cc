#include "test_domain.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <regex>
#include <stdexcept>

namespace telegrasp::testing {
namespace {

constexpr int kMaxDomain = 232;  // the largest domain whose RTPS ports fit in 16 bits

// RTPS well-known ports (DDSI-RTPS 9.6.1.1, Fast DDS defaults): PB + DG * domain + offset.
constexpr int kPortBase = 7400, kDomainGain = 250, kDiscoveryMulticastOffset = 0, kDiscoveryUnicastOffset = 10;

// Where the next lease of this process starts looking (-1: not yet chosen), so that successive
// leases do not hand out a domain just released.
std::mutex cursor_mutex;
int cursor = -1;

// Whether a UDP socket without SO_REUSEADDR can bind `port` on every address: false when any
// socket (Fast DDS's, reused or not) holds it.
bool udp_port_free(int port) {
  const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (s < 0) return true;  // cannot tell: do not block the lease on it
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool bound = ::bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  const int error = errno;
  ::close(s);
  return bound || error != EADDRINUSE;
}

// Fast DDS's shared-memory port `port`: its segment file; its lock files add "_el" or "_sl".
std::string shm_port_file(int port) { return "/dev/shm/fastrtps_port" + std::to_string(port); }

// Whether some process holds a file lock on `path`: its device and inode in /proc/locks. Only read,
// never locked here: a participant taking its own lock at that moment must not fail.
bool file_locked(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;
  char id[64];
  std::snprintf(id, sizeof id, "%02x:%02x:%lu", ::major(st.st_dev), ::minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  for (std::string token; locks >> token;)
    if (token == id) return true;
  return false;
}

void make_lock_dir(const std::string& dir) {
  if (::mkdir(dir.c_str(), 0777) == 0) {
    ::chmod(dir.c_str(), 01777);  // every user's tests share it, as /tmp itself
    return;
  }
  const int error = errno;
  struct stat st {};
  if (error != EEXIST || ::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw std::runtime_error("DomainLease: cannot make the lock folder " + dir + ": " + std::strerror(error));
}

// The descriptor holding the lock on `domain`'s file in `dir`, or -1 if another holder has it.
int try_lock(const std::string& dir, int domain) {
  const std::string path = dir + "/" + std::to_string(domain) + ".lock";
  // Read-only is enough for flock, and works on a file another user made. Inherited by children.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CREAT, 0666);
  if (fd < 0) throw std::runtime_error("DomainLease: cannot open " + path + ": " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return fd;
  const int error = errno;
  ::close(fd);
  if (error != EWOULDBLOCK) throw std::runtime_error("DomainLease: cannot lock " + path + ": " + std::strerror(error));
  return -1;
}

}  // namespace

DomainPool test_domain_pool() {
  const char* text = std::getenv("TELEGRASP_TEST_DOMAINS");
  if (text == nullptr || *text == '\0') return {};
  std::smatch m;
  const std::string s = text;
  DomainPool r;
  if (std::regex_match(s, m, std::regex(R"((\d{1,3})-(\d{1,3}))"))) {
    r.first = std::stoi(m[1]);
    r.last = std::stoi(m[2]);
    if (r.first <= r.last && r.last <= kMaxDomain) return r;
  }
  throw std::runtime_error("TELEGRASP_TEST_DOMAINS is '" + s + "'; expected FIRST-LAST with 0 <= FIRST <= LAST <= 232");
}

void remove_shared_memory_ports(int domain) {
  const int first = kPortBase + kDomainGain * domain;
  for (int port = first; port < first + kDomainGain; ++port) {
    const std::string name = shm_port_file(port);
    for (const std::string& path :
         {name, name + "_el", name + "_sl", "/dev/shm/sem.fastrtps_port" + std::to_string(port) + "_mutex"})
      ::unlink(path.c_str());  // mostly ENOENT: nothing to remove
  }
}

bool domain_ports_in_use(int domain) {
  const int base = kPortBase + kDomainGain * domain;
  // Over shared memory, every live participant of the domain holds a shared lock on the file
  // beside its discovery multicast port.
  return !udp_port_free(base + kDiscoveryMulticastOffset) || !udp_port_free(base + kDiscoveryUnicastOffset) ||
         file_locked(shm_port_file(base + kDiscoveryMulticastOffset) + "_sl");
}

DomainLease::DomainLease(int count, const DomainPool& pool) {
  if (pool.first < 0 || pool.first > pool.last || pool.last > kMaxDomain)
    throw std::invalid_argument("DomainLease: domains " + std::to_string(pool.first) + ".." +
                                std::to_string(pool.last) + " are not within 0..232");
  const int size = pool.last - pool.first + 1;
  if (count < 1 || count > size)
    throw std::invalid_argument("DomainLease: " + std::to_string(count) + " domains asked for; the range " +
                                std::to_string(pool.first) + ".." + std::to_string(pool.last) + " has " +
                                std::to_string(size));
  make_lock_dir(pool.lock_dir);
  std::lock_guard lock(cursor_mutex);
  // A process's first lease starts at the bottom of the pool: processes started together try the
  // same files, and the locks alone keep them apart.
  if (cursor < 0) cursor = 0;
  for (int tried = 0; tried < size; ++tried) {
    const int first = pool.first + (cursor + tried) % size;
    if (first + count - 1 > pool.last) continue;  // blocks do not wrap around
    for (int d = first; d < first + count; ++d) {
      const int fd = try_lock(pool.lock_dir, d);
      // Held by another lease, or used by a program that takes none: give this block up.
      if (fd < 0 || domain_ports_in_use(d)) {
        if (fd >= 0) ::close(fd);
        break;
      }
      fds_.push_back(fd);
    }
    if (static_cast<int>(fds_.size()) == count) {
      for (int d = first; d < first + count; ++d) remove_shared_memory_ports(d);
      first_ = first;
      cursor = (first - pool.first + count) % size;
      return;
    }
    for (int fd : fds_) ::close(fd);
    fds_.clear();
  }
  throw std::runtime_error("DomainLease: no " + std::to_string(count) + " consecutive free DDS domains in " +
                           std::to_string(pool.first) + ".." + std::to_string(pool.last) +
                           ": other test processes hold them (lock files in " + pool.lock_dir +
                           ") or other DDS programs use them; set TELEGRASP_TEST_DOMAINS=FIRST-LAST for another range");
}

DomainLease::~DomainLease() {
  for (int fd : fds_) ::close(fd);
}

DomainLease::DomainLease(DomainLease&& other) noexcept : first_(other.first_), fds_(std::move(other.fds_)) {
  other.first_ = -1;
  other.fds_.clear();
}

int DomainLease::domain(int i) const {
  if (i < 0 || i >= count())
    throw std::out_of_range("DomainLease::domain(" + std::to_string(i) + ") of " + std::to_string(count()));
  return first_ + i;
}

}  // namespace telegrasp::testing

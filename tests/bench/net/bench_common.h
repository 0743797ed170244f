// Shared pieces of the network benchmarks (telegrasp-bench-latency, telegrasp-bench-scale):
// the deprecated --hz flag, the server child process, profile loading (the entities are
// idl::DdsParticipant's), ServerStatus collection, CPU time from /proc, and latency summaries.
#pragma once

#include "child_process.h"
#include "telegrasp/idl/cli.h"
#include "test_domain.h"

#include "telegrasp/idl/dds_participant.h"
#include "telegrasp/idl/network_flags.h"
#include "telegrasp/idl/telegrasp.h"

#include <fastdds/dds/subscriber/DataReaderListener.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <sys/types.h>
#include <thread>
#include <vector>

namespace telegrasp::bench {

namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

/// steady_clock now, in ns since its epoch (the one clock every benchmark timestamp uses).
std::int64_t now_ns();

// ---------------------------------------------------------------------------------------------
// Command line (the option loop is cli::for_each_option).

/// The options both network benchmarks take: the controller rate, the server they start, how they
/// reach it and where the results go. Each benchmark's Options extends it.
struct CommonOptions {
  double sample_hz = 90;
  double tick_hz = 0;  // 0: the server's default
  std::string json;
  std::string profile = "loopback";
  std::string profiles_file;
  int domain = -1;  // -1: lease one
  std::string server;
  std::vector<std::string> server_args;
  std::string server_log;
  bool late_latch = true;
};

/// Runs `run(o)` on o.domain, or, when none was given (-1), on a domain leased for the run, which
/// no test run or other benchmark uses meanwhile (the server and the children hold it too).
/// Prints what `run` throws, naming `tool`, and returns cli::kExitFailure then; else what it returns.
template <class Options, class Run>
int run_on_domain(const char* tool, Options& o, Run run) {
  try {
    std::optional<telegrasp::testing::DomainLease> lease;
    if (o.domain < 0) {
      lease.emplace();
      o.domain = lease->domain();
    }
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << tool << ": " << e.what() << "\n";
    return cli::kExitFailure;
  }
}

/// Takes flag `f` into `o` if it is one of CommonOptions' (--sample-hz, --hz, --tick-hz, --json,
/// --profile, --profiles, --domain, --server, --server-arg, --server-log, --no-late-latch);
/// `value()` gives its value, `usage_error` rejects a bad one. False for any other flag.
template <class Value>
bool parse_common_option(const char* tool, const std::string& f, const Value& value, CommonOptions& o,
                         void (*usage_error)(const std::string&)) {
  if (f == "--sample-hz")
    o.sample_hz = cli::parse_number(f, value(), 1, 1000, usage_error);
  else if (f == "--hz")
    // --hz was the controller sample rate per hand until --sample-hz (the tick rate is --tick-hz).
    cli::warn_renamed(tool, f, "--sample-hz"), o.sample_hz = cli::parse_number(f, value(), 1, 1000, usage_error);
  else if (f == "--tick-hz")
    o.tick_hz = cli::parse_number(f, value(), 1, 2000, usage_error);
  else if (f == "--json")
    o.json = value();
  else if (idl::parse_network_flag(f, value, o, usage_error))
    ;
  else if (f == "--server")
    o.server = value();
  else if (f == "--server-arg")
    o.server_args.push_back(value());
  else if (f == "--server-log")
    o.server_log = value();
  else if (f == "--no-late-latch")
    o.late_latch = false;
  else
    return false;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Signals and child processes.

/// SIGINT/SIGTERM set the flag stop_requested() returns; the benchmarks then wind down and clean up.
void install_signal_handlers();
bool stop_requested();
/// Sleeps `seconds`, returning early (false) if a stop was requested.
bool sleep_unless_stopped(double seconds);

/// Ends the process if it is still running `seconds` after construction, or 15 s after a stop was
/// requested: it SIGTERMs (then SIGKILLs) every live ChildProcess and calls _exit(1). A hang
/// inside Fast DDS must not leave a server behind.
class Watchdog {
 public:
  explicit Watchdog(double seconds);
  ~Watchdog();
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

 private:
  std::atomic<bool> done_{false};
  std::thread thread_;
};

/// This executable's path (/proc/self/exe) and the telegrasp-server next to it.
std::string self_exe();
std::string default_server_path();

/// Child processes: the shared ChildProcess (client_lib/tools/common); the watchdog stops every live one.
using tools::ChildProcess;

// ---------------------------------------------------------------------------------------------
// CPU time from /proc.

/// utime + stime of a process (all its threads) or of one thread, in microseconds; -1 if unreadable.
std::int64_t process_cpu_us(pid_t pid);
std::int64_t thread_cpu_us(pid_t pid, pid_t tid);
/// CPU time (us) of every thread of a process, by thread id (Fast DDS 2.9 leaves its threads
/// unnamed, so the id and its creation order are all there is).
std::map<pid_t, std::int64_t> threads_cpu_us(pid_t pid);
/// This process's CPU time (getrusage), in microseconds.
std::int64_t self_cpu_us();
/// CPU time every core of the machine spent busy (not idle or iowait) since boot, /proc/stat, us.
std::int64_t machine_busy_us();
/// Bytes and packets the loopback interface carried since it came up (/proc/net/dev, received
/// side: every packet sent on `lo` is received on it once). Inside `unshare -n` with the `udp`
/// profile that is exactly this run's DDS traffic; {-1, -1} if unreadable.
struct InterfaceCounters {
  std::int64_t bytes = -1, packets = -1;
};
InterfaceCounters loopback_counters();

// ---------------------------------------------------------------------------------------------
// Fast DDS.

/// Loads the XML profiles file ("" = the default one), checks the participant profile, and turns
/// Fast DDS intraprocess delivery off: the benchmarks run several participants in one process,
/// and with intraprocess delivery Fast DDS 2.9.1 deadlocks in the Writer Liveliness Protocol (two
/// participants' event threads lock each other's PDP mutex: eProsima/Fast-DDS#3115; seen here with
/// 17 participants and AUTOMATIC liveliness). Samples between them then go through shared memory,
/// as between processes.
void load_profiles(const std::string& file, const std::string& participant_profile);

/// Matched remote endpoints of a writer / reader.
int matched_readers(dds::DataWriter* writer);
int matched_writers(dds::DataReader* reader);
/// Polls `ready` every 10 ms until it is true, `timeout_s` passes, or a stop is requested.
bool wait_until(const std::function<bool()>& ready, double timeout_s);

// ---------------------------------------------------------------------------------------------
// The server.

struct ServerOptions {
  std::string path;  ///< telegrasp-server executable.
  int domain = 0;
  std::string profile = "loopback";
  std::string profiles_file;  ///< "" = the server's default.
  bool late_latch = true;
  double tick_hz = 0;  ///< The server's --tick-hz; 0 = its default.
  bool empty_scene = true;  ///< --empty-scene; false: the scene of the configuration (--config in `extra`).
  std::vector<std::string> extra;  ///< More arguments (--server-arg).
  std::string log_path;
};

/// The server a benchmark starts, from its common options (log_path and extra arguments are the
/// benchmark's own).
ServerOptions server_options(const CommonOptions& o);

/// The command line the server is started with (also printed in reports).
std::vector<std::string> server_argv(const ServerOptions& o);

/// Every ServerStatus the benchmark receives from its own server, stamped with its arrival time
/// and the server's CPU times at arrival (so CPU and tick windows line up). Once a server pid is
/// set, statuses of other processes (another server on the same domain) are ignored but counted:
/// a Fast DDS 2.9 GUID prefix carries the low 16 bits of the writer's process id in bytes 4..5
/// (little endian; checked: pid 0x375b -> 01.0f.78.fd.5b.37.fc.9c...).
class StatusCollector : public dds::DataReaderListener {
 public:
  struct Record {
    std::int64_t received_ns = 0;
    std::int64_t server_cpu_us = -1;  ///< whole process
    std::int64_t sim_thread_cpu_us = -1;  ///< the server's main thread (its simulation thread)
    std::int64_t self_cpu_us = -1;  ///< the benchmark process
    std::int64_t machine_busy_us = -1;  ///< every process of the machine
    InterfaceCounters lo;  ///< the loopback interface
    msg::ServerStatus status;
  };
  void set_server_pid(pid_t pid) { server_pid_ = pid; }
  void on_data_available(dds::DataReader* reader) override;
  std::size_t count() const;
  std::size_t foreign() const { return foreign_.load(); }  ///< Statuses from other processes.
  std::optional<Record> latest() const;
  std::vector<Record> since(std::int64_t t_ns) const;  ///< Records received at or after t_ns.
  /// Waits until a record received at or after `after_ns` satisfies `pred` (or any, if empty).
  std::optional<Record> wait_for(std::int64_t after_ns, double timeout_s,
                                 const std::function<bool(const msg::ServerStatus&)>& pred = {});

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Record> records_;
  std::atomic<pid_t> server_pid_{0};
  std::atomic<std::size_t> foreign_{0};
};

/// Checks that no other telegrasp-server answers on the domain (1.5 s), starts the server and
/// waits for its first ServerStatus on `collector`'s reader; throws std::runtime_error (with the
/// server's log tail) if the domain is taken, or the server exits or stays silent for `timeout_s`.
void start_server(ChildProcess& child, const ServerOptions& o, StatusCollector& collector, double timeout_s);

// ---------------------------------------------------------------------------------------------
// Results.

/// Nearest-rank percentiles of a set of latencies (us).
struct Summary {
  std::size_t count = 0;
  double p50 = 0, p90 = 0, p99 = 0, max = 0, mean = 0;
};
Summary summarize(std::vector<double> values);

/// A unit quaternion (w, x, y, z) for a smooth wobble: rotation by `angle` about a tilted axis.
msg::Quat wobble_quaternion(double angle);

/// Controller sample `seq` of hand `side` of client number `client` at `t` s into the run: the
/// palm moves smoothly in the air above the table (top z = 0, |x|, |y| <= 2 m), 0.35..0.55 m up,
/// at x < 0 where no default-layout object stands (objects start at x = 0.35); the orientation
/// wobbles and the trigger oscillates 0..1 at 0.5 Hz.
msg::ControllerState controller_sample(const std::string& client_id, int client, int side, std::uint64_t seq, double t);

/// Shell-quoted command line, for reports.
std::string join_command(const std::vector<std::string>& argv);

}  // namespace telegrasp::bench

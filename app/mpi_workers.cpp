#include "app/mpi_workers.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#ifdef GABION_HAVE_MPI
// (the C interface only: no MPI C++ bindings to link)
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace gabion::app {

using nlohmann::json;

int MpiSession::launcherSize() {
  // (Open MPI's mpirun; MPICH's and Slurm's PMI; PMIx without a size: ask MPI)
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* v = std::getenv(name)) return std::max(1, std::atoi(v));
  if (std::getenv("PMIX_RANK") != nullptr) return 2;
  return 1;
}

#ifdef GABION_HAVE_MPI

namespace {

constexpr int kTagTask = 1, kTagAnswer = 2, kTagStop = 3;

// Every MPI call is made under this lock (MPI_THREAD_SERIALIZED): rank 0's
// threads each wait for their own worker's answer by probing, not blocking.
std::mutex& mpiLock() {
  static std::mutex m;
  return m;
}

void sendText(const std::string& text, int to, int tag) {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, to, tag, MPI_COMM_WORLD);
}

class WorkerRanks final : public RankPool {
 public:
  explicit WorkerRanks(int size) {
    for (int r = size - 1; r >= 1; --r) free_.push_back(r);
    size_ = size - 1;
  }
  ~WorkerRanks() override {
    const std::lock_guard<std::mutex> lock(mpiLock());
    for (int r = 1; r <= size_; ++r) MPI_Send(nullptr, 0, MPI_CHAR, r, kTagStop, MPI_COMM_WORLD);
  }
  int size() const override { return size_ + (here_ ? 1 : 0); }
  void workHere(TaskHandler handler) override { here_ = std::move(handler); }

  json call(const json& task) override {
    if (here_ && !here_busy_.exchange(true)) {
      struct Free {  // (rank 0 is free again however the task ends)
        std::atomic<bool>& busy;
        ~Free() { busy = false; }
      } free{here_busy_};
      return here_(task);
    }
    const int w = take();
    struct Give {  // (the worker is free again however this call ends)
      WorkerRanks& self;
      int w;
      ~Give() { self.give(w); }
    } give{*this, w};
    {
      const std::lock_guard<std::mutex> lock(mpiLock());
      sendText(task.dump(), w, kTagTask);
    }
    std::string reply;
    for (auto wait = std::chrono::microseconds(20);; wait = std::min(2 * wait, std::chrono::microseconds(100))) {
      {
        const std::lock_guard<std::mutex> lock(mpiLock());
        int flag = 0;
        MPI_Status status;
        MPI_Iprobe(w, kTagAnswer, MPI_COMM_WORLD, &flag, &status);
        if (flag != 0) {
          int count = 0;
          MPI_Get_count(&status, MPI_CHAR, &count);
          reply.resize(static_cast<std::size_t>(count));
          MPI_Recv(reply.data(), count, MPI_CHAR, w, kTagAnswer, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
          break;
        }
      }
      std::this_thread::sleep_for(wait);
    }
    const json answer = json::parse(reply);
    // (the worker's message as it is: a failed task is recorded as the
    // serial run records it)
    if (answer.contains("error")) throw std::runtime_error(answer.at("error").get<std::string>());
    return answer.at("value");
  }

 private:
  int take() {
    std::unique_lock<std::mutex> lock(mutex_);
    freed_.wait(lock, [&] { return !free_.empty(); });
    const int w = free_.back();
    free_.pop_back();
    return w;
  }
  void give(int w) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(w);
    }
    freed_.notify_one();
  }
  int size_ = 0;
  TaskHandler here_;
  std::atomic<bool> here_busy_{false};
  std::mutex mutex_;
  std::condition_variable freed_;
  std::vector<int> free_;
};

}  // namespace

bool MpiSession::available() {
  return true;
}

MpiSession::MpiSession(int& argc, char**& argv) {
  if (launcherSize() <= 1) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  initialised_ = true;
  if (provided < MPI_THREAD_SERIALIZED) {
    MPI_Finalize();
    throw std::runtime_error("this MPI library cannot be called from several threads one at a time");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() {
  if (initialised_) MPI_Finalize();
}

void serveTasks(const MpiSession& session, const TaskHandler& handler) {
  (void)session;
  for (;;) {
    // (waiting by probing with growing pauses, not in MPI_Probe, which spins
    // a core while rank 0 has nothing to send: on a shared or
    // oversubscribed node that core is someone's work)
    MPI_Status status;
    int flag = 0;
    for (auto wait = std::chrono::microseconds(20);; wait = std::min(2 * wait, std::chrono::microseconds(500))) {
      MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
      if (flag != 0) break;
      std::this_thread::sleep_for(wait);
    }
    int count = 0;
    MPI_Get_count(&status, MPI_CHAR, &count);
    std::string text(static_cast<std::size_t>(count), '\0');
    MPI_Recv(text.data(), count, MPI_CHAR, 0, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (status.MPI_TAG == kTagStop) return;
    json answer;
    try {
      answer["value"] = handler(json::parse(text));
    } catch (const std::exception& e) {
      answer = {{"error", e.what()}};
    }
    sendText(answer.dump(), 0, kTagAnswer);
  }
}

std::unique_ptr<RankPool> workerRanks(const MpiSession& session) {
  return std::make_unique<WorkerRanks>(session.size());
}

#else  // a build without MPI: one process, and mpirun on several ranks is refused

bool MpiSession::available() {
  return false;
}

MpiSession::MpiSession(int& /*argc*/, char**& /*argv*/) {}

MpiSession::~MpiSession() = default;

void serveTasks(const MpiSession& /*session*/, const TaskHandler& /*handler*/) {
  throw std::logic_error("serveTasks: this build has no MPI");
}

std::unique_ptr<RankPool> workerRanks(const MpiSession& /*session*/) {
  throw std::logic_error("workerRanks: this build has no MPI");
}

#endif

}  // namespace gabion::app

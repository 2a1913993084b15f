// SPDX-License-Identifier: BSD-3-Clause
#include "Batch.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numeric>
#include <system_error>

#ifdef DYNAMICPOINTS_HAS_MPI
#include "vtkMPI.h"
#include "vtkMPIController.h"
#include "vtkSMPTools.h"

#include <tbb/global_control.h>

#include <thread>
#endif

namespace dp::cli
{
namespace fs = std::filesystem;

namespace
{

std::uintmax_t filesIn(const fs::path& folder)
{
  std::uintmax_t bytes = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error))
    if (entry.is_regular_file(error))
      bytes += entry.file_size(error);
  return bytes;
}

} // namespace

std::vector<BatchInput> describeBatch(const std::vector<std::string>& paths)
{
  std::vector<BatchInput> inputs;
  std::map<std::string, int> seen;
  for (const std::string& path : paths)
  {
    // "takes/jump/" names the folder "jump"; a .series file stands for its folder's frames.
    const fs::path p = fs::path(path).lexically_normal();
    const fs::path named = p.has_filename() ? p : p.parent_path();
    std::error_code error;
    BatchInput input{path, named.stem().string(), 0};
    if (fs::is_directory(named, error))
    {
      input.name = named.filename().string();
      input.bytes = filesIn(named);
    }
    else if (named.extension() == ".series")
    {
      const fs::path folder = fs::absolute(named, error).parent_path();
      input.name = folder.filename().string();
      input.bytes = filesIn(folder);
    }
    else
    {
      const auto size = fs::file_size(named, error);
      input.bytes = error ? 0 : size;
    }
    if (input.name.empty() || input.name == "." || input.name == "..")
      input.name = "input";
    const int count = ++seen[input.name];
    if (count > 1)
      input.name += "-" + std::to_string(count);
    inputs.push_back(std::move(input));
  }
  return inputs;
}

std::vector<std::size_t> largestFirst(const std::vector<BatchInput>& inputs)
{
  std::vector<std::size_t> order(inputs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return inputs[a].bytes > inputs[b].bytes; });
  return order;
}

struct Ranks::Impl
{
#ifdef DYNAMICPOINTS_HAS_MPI
  vtkMPIController* Controller = nullptr;
  std::unique_ptr<tbb::global_control> Threads; // this process's share of the machine
  MPI_Win Counter = MPI_WIN_NULL;               // takeNext's counter, on rank 0
  int* CounterMemory = nullptr;
#endif
  int LocalCounter = 0; // one process
};

namespace
{

// Open MPI, MPICH and PMIx launchers announce themselves in the environment.
bool startedByMpiLauncher()
{
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(name))
      return true;
  return false;
}

// How many processes of the run share this machine (the launcher says; else all of them).
int processesOnThisMachine(int processes)
{
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"})
    if (const char* value = std::getenv(name))
      if (const int local = std::atoi(value); local > 0)
        return local;
  return processes;
}

} // namespace

Ranks::Ranks(int* argc, char*** argv) : P(std::make_unique<Impl>())
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (startedByMpiLauncher())
  {
    P->Controller = vtkMPIController::New();
    P->Controller->Initialize(argc, argv);
    // Each process takes its share of the cores for its threads (TBB: the engine's loops and
    // VTK's SMP tools): more threads than cores only make them wait for each other.
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const int share = std::max(1, cores / processesOnThisMachine(size()));
    P->Threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       static_cast<std::size_t>(share));
    vtkSMPTools::Initialize(share);
  }
#else
  (void)argc;
  (void)argv;
  (void)startedByMpiLauncher;
  (void)processesOnThisMachine;
#endif
}

Ranks::~Ranks()
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller)
  {
    if (P->Counter != MPI_WIN_NULL)
      MPI_Win_free(&P->Counter);
    P->Controller->Finalize();
    P->Controller->Delete();
  }
#endif
}

int Ranks::rank() const
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller)
    return P->Controller->GetLocalProcessId();
#endif
  return 0;
}

int Ranks::size() const
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller)
    return P->Controller->GetNumberOfProcesses();
#endif
  return 1;
}

std::vector<std::string> Ranks::gather(const std::string& mine) const
{
  std::vector<std::string> all;
  if (size() == 1)
    return {mine};
#ifdef DYNAMICPOINTS_HAS_MPI
  constexpr int LengthTag = 8101, TextTag = 8102;
  vtkMPIController* c = P->Controller;
  if (rank() != 0)
  {
    vtkIdType length = static_cast<vtkIdType>(mine.size());
    c->Send(&length, 1, 0, LengthTag);
    c->Send(mine.data(), length, 0, TextTag);
    return all;
  }
  all.push_back(mine);
  for (int r = 1; r < size(); ++r)
  {
    vtkIdType length = 0;
    c->Receive(&length, 1, r, LengthTag);
    std::string text(static_cast<std::size_t>(length), '\0');
    c->Receive(text.data(), length, r, TextTag);
    all.push_back(std::move(text));
  }
#endif
  return all;
}

void Ranks::shareCounter()
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller && P->Counter == MPI_WIN_NULL)
  {
    // One int on rank 0 that every rank reads and increments atomically.
    const MPI_Aint bytes = rank() == 0 ? sizeof(int) : 0;
    MPI_Win_allocate(bytes, sizeof(int), MPI_INFO_NULL, MPI_COMM_WORLD, &P->CounterMemory,
                     &P->Counter);
    if (rank() == 0)
      *P->CounterMemory = 0;
    MPI_Barrier(MPI_COMM_WORLD); // the counter is set before anyone takes from it
  }
#endif
}

int Ranks::takeNext()
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller)
  {
    const int one = 1;
    int taken = 0;
    MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, P->Counter);
    MPI_Fetch_and_op(&one, &taken, MPI_INT, 0, 0, MPI_SUM, P->Counter);
    MPI_Win_unlock(0, P->Counter);
    return taken;
  }
#endif
  return P->LocalCounter++;
}

int Ranks::broadcast(int value) const
{
#ifdef DYNAMICPOINTS_HAS_MPI
  if (P->Controller)
    P->Controller->Broadcast(&value, 1, 0);
#endif
  return value;
}

} // namespace dp::cli

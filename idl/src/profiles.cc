#include "telegrasp/idl/profiles.h"

#include "telegrasp/sim/data_paths.h"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <set>
#include <stdexcept>

namespace telegrasp::idl {

std::string default_profiles_file() {
  if (const char* env = std::getenv("TELEGRASP_PROFILES"); env != nullptr && *env != '\0') return env;
  return (sim::data_dir() / "telegrasp_profiles.xml").string();
}

void load_profiles(const std::string& path_in, const std::string& participant_profile) {
  using eprosima::fastdds::dds::DomainParticipantFactory;
  static std::mutex mutex;
  static std::set<std::string> loaded;
  const std::string path = path_in.empty() ? default_profiles_file() : path_in;
  std::lock_guard lock(mutex);
  if (!loaded.count(path)) {
    if (!std::filesystem::is_regular_file(path))
      throw std::runtime_error("Fast DDS profiles file " + path +
                               " does not exist (set --profiles or TELEGRASP_PROFILES)");
    if (DomainParticipantFactory::get_instance()->load_XML_profiles_file(path) != ReturnCode_t::RETCODE_OK)
      throw std::runtime_error("Fast DDS profiles file " + path + " is not valid Fast DDS XML");
    loaded.insert(path);
  }
  eprosima::fastdds::dds::DomainParticipantQos qos;
  if (DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(participant_profile, qos) !=
      ReturnCode_t::RETCODE_OK)
    throw std::runtime_error("no participant profile '" + participant_profile + "' in " + path +
                             " (shipped: " + kShippedProfiles + ")");
}

}  // namespace telegrasp::idl

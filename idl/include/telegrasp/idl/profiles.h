// Finding and loading the Fast DDS XML profiles (deploy/fastdds/telegrasp_profiles.xml).
#pragma once

#include <string>

namespace telegrasp::idl {

/// The participant profiles deploy/fastdds/telegrasp_profiles.xml defines, for messages and help.
inline constexpr const char* kShippedProfiles = "loopback, shm, udp, lan, wan, secure";

/// The profiles file to use when none is given: $TELEGRASP_PROFILES if set, else the shipped copy
/// of deploy/fastdds/telegrasp_profiles.xml in the data folder (sim::data_dir():
/// <prefix>/share/telegrasp once installed, build/share/telegrasp in a build tree).
std::string default_profiles_file();

/// Loads `path` (or default_profiles_file() if empty) into Fast DDS once per process and checks
/// that `participant_profile` is defined in it. Throws std::runtime_error naming the file or the
/// profile that is wrong. Safe to call again with the same file.
void load_profiles(const std::string& path, const std::string& participant_profile);

}  // namespace telegrasp::idl

// Topic names and Fast DDS XML profile names: the one place both server and clients read them.
#pragma once

namespace telegrasp::idl {

/// Topic names (types in telegrasp.idl, module telegrasp::msg).
inline constexpr const char* kControllerStateTopic = "telegrasp/ControllerState";
inline constexpr const char* kHandSkeletonTopic = "telegrasp/HandSkeleton";
inline constexpr const char* kGraspStateTopic = "telegrasp/GraspState";
inline constexpr const char* kContactSetTopic = "telegrasp/ContactSet";
inline constexpr const char* kGraspEventTopic = "telegrasp/GraspEvent";
inline constexpr const char* kSceneStateTopic = "telegrasp/SceneState";
inline constexpr const char* kSceneCommandTopic = "telegrasp/SceneCommand";
inline constexpr const char* kServerStatusTopic = "telegrasp/ServerStatus";
inline constexpr const char* kObjectGeometryTopic = "telegrasp/ObjectGeometry";
inline constexpr const char* kClientNoticeTopic = "telegrasp/ClientNotice";
/// The scene directory (SceneAnnouncement): the one topic in kDirectoryPartition; every other
/// topic is in the scene's partition, kScenePartitionPrefix + scene name.
inline constexpr const char* kSceneDirectoryTopic = "telegrasp/SceneDirectory";

/// DDS partitions: a scene's topics in "telegrasp/scene/<name>", the directory in
/// "telegrasp/directory" (network.h).
inline constexpr const char* kScenePartitionPrefix = "telegrasp/scene/";
inline constexpr const char* kDirectoryPartition = "telegrasp/directory";
inline constexpr const char* kDefaultScene = "default";

/// Participant profiles in deploy/fastdds/telegrasp_profiles.xml (transport and discovery).
inline constexpr const char* kDefaultParticipantProfile = "loopback";

/// Writer and reader profile of a topic: "<topic>.writer" and "<topic>.reader" in the XML, e.g.
/// "telegrasp/ControllerState.writer" (QoS: reliability, durability, history, deadline ...).
inline constexpr const char* kWriterSuffix = ".writer";
inline constexpr const char* kReaderSuffix = ".reader";

/// Hand sides, as in the hand_side keys.
inline constexpr unsigned char kHandLeft = 0;
inline constexpr unsigned char kHandRight = 1;

}  // namespace telegrasp::idl

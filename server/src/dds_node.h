// DdsNode: the one owner of the server's Fast DDS entities. Its listeners only hand samples to
// the InputMailbox (controller states) or a command queue (after InputMailbox::admit_command), and
// tell it when a participant leaves; publishing is an OutputSink.
#pragma once

#include "input_mailbox.h"
#include "output_sink.h"
#include "process_stats.h"
#include "scene_directory.h"

#include "telegrasp/idl/network.h"

#include <memory>
#include <string>
#include <vector>

namespace telegrasp::server {

class DdsNode final : public OutputSink {
 public:
  /// Joins `domain` with the participant profile `profile` of `profiles_file` ("" = default), in
  /// `network`'s scene (DDS partition) and through its discovery servers, if any.
  /// With a DDS Security profile (`secure`), every client id is bound to the certificate subject
  /// that first drove it (identity.h): another identity's samples for it are refused and counted
  /// as client_id_owned_by_another_participant.
  /// Throws std::runtime_error naming the profile, topic or entity that could not be created.
  DdsNode(int domain, const std::string& profile, const std::string& profiles_file, InputMailbox& mailbox,
          const idl::Network& network = {});
  ~DdsNode() override;
  DdsNode(const DdsNode&) = delete;
  DdsNode& operator=(const DdsNode&) = delete;

  /// Publishes the ObjectGeometry of every model (make_object_geometry), one instance per model
  /// name; the writer keeps them for subscribers that join later. Models are fixed for a server's
  /// life, so this is called once, at start-up. A model whose mesh is over
  /// OBJECT_GEOMETRY_MAX_TRIANGLES, or whose sample cannot be written, is named on stderr; the
  /// server goes on.
  void publish_geometries(const std::vector<sim::ObjectModelPtr>& models);

  /// The scene served (resolved: never empty).
  const std::string& scene() const;

  /// Claims the scene on the directory: announces `facts` (not serving yet). From then on every
  /// ServerStatus published also announces the run (make_announcement), and the destructor
  /// withdraws it. Call once.
  void announce(const AnnouncerFacts& facts);
  /// The live announcements of other server runs on the directory (every scene), as read now.
  std::vector<msg::SceneAnnouncement> directory();

  /// Scene commands received since the last call, in arrival order.
  std::vector<msg::SceneCommand> take_commands();

  void publish(const msg::HandSkeleton& skeleton) override;
  void publish(const msg::GraspState& state) override;
  void publish(const msg::ContactSet& contacts) override;
  void publish(const msg::GraspEvent& event) override;
  void publish(const msg::SceneState& scene) override;
  void publish(const msg::ServerStatus& status) override;
  /// Thread-safe (input refusals come from DDS listener threads). One instance per client; beyond
  /// kMaxNoticeInstances the oldest client's instance is unregistered.
  void publish(const msg::ClientNotice& notice) override;
  void hand_removed(const HandAddress& hand) override;

 private:
  static constexpr std::size_t kMaxNoticeInstances = 512;
  void announce_status(const msg::ServerStatus& status);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace telegrasp::server

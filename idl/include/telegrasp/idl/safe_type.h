// SafeType: a fastddsgen PubSubType whose deserialize() never throws.
#pragma once

#include <fastcdr/exceptions/Exception.h>
#include <fastdds/rtps/common/SerializedPayload.h>

namespace telegrasp::idl {

/// `PubSubType` with deserialize() returning false on any malformed payload. fastddsgen 2.3's
/// code catches only NotEnoughMemoryException, so a sample whose boolean byte is neither 0 nor 1
/// (fastcdr's BadParamException) threw out of DataReader::take_next_sample and terminated the
/// reading process: one malformed network sample stopped the server (found by
/// telegrasp-fuzz-controller-state). Every reader and writer of DdsParticipant uses it.
template <class PubSubType>
class SafeType : public PubSubType {
 public:
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    try {
      return PubSubType::deserialize(payload, data);
    } catch (const eprosima::fastcdr::exception::Exception&) {
      return false;
    }
  }
};

}  // namespace telegrasp::idl

// Forward declarations of the Fast DDS types the idl headers name only by reference, so that
// including them does not pull in Fast DDS.
#pragma once

namespace eprosima::fastdds::dds {
class DomainParticipantQos;
}  // namespace eprosima::fastdds::dds

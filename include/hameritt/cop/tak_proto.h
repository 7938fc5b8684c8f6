#pragma once
// TAK Protocol Version 1: a CoT event as the protobuf message atakmap.commoncommo.protobuf.v1
// .TakMessage (the TAK .proto files takmessage, cotevent, detail, contact and track, proto3 wire
// format), and its two framings from TAK's protocol.txt: the mesh (UDP) header 0xbf 0x01 0xbf
// and the stream header 0xbf <varint payload length>. Encoded by hand (no protobuf runtime); the
// field numbers are TAK's:
//   TakMessage { TakControl takControl = 1; CotEvent cotEvent = 2; }
//   CotEvent { string type = 1; access = 2; qos = 3; opex = 4; uid = 5; uint64 sendTime = 6;
//              startTime = 7; staleTime = 8 (ms since the epoch); string how = 9;
//              double lat = 10; lon = 11; hae = 12; ce = 13; le = 14; Detail detail = 15; }
//   Detail { string xmlDetail = 1; Contact contact = 2; Group group = 3;
//            PrecisionLocation precisionLocation = 4; Status status = 5; Takv takv = 6;
//            Track track = 7; }
//   Contact { string endpoint = 1; string callsign = 2; }   Track { double speed = 1; course = 2; }

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "hameritt/cop/cot.h"

namespace hameritt::cop {

// How events are written on the wire: CoT XML ("TAK Protocol Version 0") or TAK Protocol
// Version 1 (protobuf).
enum class TakEncoding { kXml, kProtobuf };

// Parses "xml" or "protobuf"; throws std::invalid_argument naming `what` and the value.
TakEncoding parseTakEncoding(const std::string& value, const std::string& what);
const char* toString(TakEncoding encoding);

// Appends `value` as a protobuf varint (7 bits a byte, least significant group first).
void appendVarint(std::string& out, std::uint64_t value);

// Reads a varint at `pos` (advanced past it); false if the input ends first or it exceeds 10
// bytes.
bool readVarint(std::string_view in, std::size_t& pos, std::uint64_t& value);

// The event as a serialized TakMessage (the payload, no header). <contact> and <track> become
// the protobuf fields; the rest of <detail> travels in xmlDetail.
std::string toTakProto(const CotEvent& e);

// Mesh (UDP) message: 0xbf 0x01 0xbf, then the payload.
std::string frameMesh(std::string_view payload);

// Streaming message: 0xbf, the payload's length as a varint, then the payload.
std::string frameStream(std::string_view payload);

// A malformed TAK Protocol stream.
class TakFrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Takes one streaming message off the front of `buffer` into `payload`: false when the buffer
// holds only part of one (nothing is taken). Throws TakFrameError when the first byte is not
// 0xbf or the length varint is longer than 10 bytes.
bool takeStreamFrame(std::string& buffer, std::string& payload);

// Streaming protocol negotiation (TAK's protocol.txt): the server offers TAK Protocol Version 1
// in an XML event t-x-takp-v (<TakControl><TakProtocolSupport version="1"/>), the client asks
// with t-x-takp-q (<TakRequest version="1"/>), the server answers t-x-takp-r (<TakResponse
// status="true"/>) and both sides switch to streaming frames.
enum class TakNegotiation { kNothing, kOffered, kAccepted, kDenied };

// The client's request for Version 1, an XML event at `now` (Unix seconds).
std::string takProtocolRequest(double now);

// Reads the complete XML events at the front of `buffer` (taking them off it) and returns the
// latest negotiation step among them: kAccepted or kDenied for a t-x-takp-r, kOffered for a
// t-x-takp-v that lists version 1, else kNothing.
TakNegotiation scanNegotiation(std::string& buffer);

}  // namespace hameritt::cop

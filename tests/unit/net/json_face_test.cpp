// The JSON face's table and its error form: every call of haptic.v1.Haptic served, with the
// service's own request and response types; errors as Connect writes them.
#include "net/json_face.hpp"
#include "net/http_face.hpp"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "haptic/v1/service.pb.h"

namespace haptic::net {
namespace {

const google::protobuf::ServiceDescriptor& haptic_service() {
  const auto* service = v1::OpenSessionRequest::descriptor()->file()->pool()->FindServiceByName(
      "haptic.v1.Haptic");
  EXPECT_NE(service, nullptr);
  return *service;
}

google::protobuf::Struct parsed(const std::string& json) {
  google::protobuf::Struct out;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &out);
  EXPECT_TRUE(status.ok()) << json << ": " << status.ToString();
  return out;
}

TEST(JsonFace, EveryUnaryCallOfTheServiceIsServedWithItsOwnTypes) {
  const auto& service = haptic_service();
  std::map<std::string, const FaceMethod*> served;
  const std::vector<FaceMethod> methods = JsonFace::methods();
  for (const FaceMethod& method : methods) {
    EXPECT_TRUE(served.emplace(std::string(method.name), &method).second) << method.name << " twice";
  }
  std::set<std::string> streams;
  for (int i = 0; i < service.method_count(); ++i) {
    const auto& method = *service.method(i);
    if (method.server_streaming() || method.client_streaming()) {
      streams.insert(method.name());
      EXPECT_FALSE(served.contains(method.name())) << method.name() << " is a stream";
      continue;
    }
    const auto found = served.find(method.name());
    ASSERT_NE(found, served.end()) << "haptic.v1.Haptic." << method.name() << " is not served";
    EXPECT_EQ(found->second->request, method.input_type()) << method.name();
    EXPECT_EQ(found->second->response, method.output_type()) << method.name();
    served.erase(found);
  }
  EXPECT_TRUE(served.empty()) << served.begin()->first << " is served but not in service.proto";
  EXPECT_EQ(streams, std::set<std::string>{"WatchEvents"});
}

TEST(JsonFace, AnErrorIsConnectsJsonUnderConnectsHttpStatus) {
  const std::map<grpc::StatusCode, std::pair<std::string, int>> expected{
      {grpc::StatusCode::CANCELLED, {"canceled", 499}},
      {grpc::StatusCode::UNKNOWN, {"unknown", 500}},
      {grpc::StatusCode::INVALID_ARGUMENT, {"invalid_argument", 400}},
      {grpc::StatusCode::DEADLINE_EXCEEDED, {"deadline_exceeded", 504}},
      {grpc::StatusCode::NOT_FOUND, {"not_found", 404}},
      {grpc::StatusCode::ALREADY_EXISTS, {"already_exists", 409}},
      {grpc::StatusCode::PERMISSION_DENIED, {"permission_denied", 403}},
      {grpc::StatusCode::RESOURCE_EXHAUSTED, {"resource_exhausted", 429}},
      {grpc::StatusCode::FAILED_PRECONDITION, {"failed_precondition", 400}},
      {grpc::StatusCode::ABORTED, {"aborted", 409}},
      {grpc::StatusCode::OUT_OF_RANGE, {"out_of_range", 400}},
      {grpc::StatusCode::UNIMPLEMENTED, {"unimplemented", 501}},
      {grpc::StatusCode::INTERNAL, {"internal", 500}},
      {grpc::StatusCode::UNAVAILABLE, {"unavailable", 503}},
      {grpc::StatusCode::DATA_LOSS, {"data_loss", 500}},
      {grpc::StatusCode::UNAUTHENTICATED, {"unauthenticated", 401}},
  };
  for (const auto& [code, want] : expected) {
    const FaceReply reply = error_reply({code, "what was wrong"});
    EXPECT_EQ(reply.code, code);
    EXPECT_EQ(reply.http_status, want.second) << want.first;
    EXPECT_EQ(reply.content_type, "application/json");
    const auto body = parsed(reply.body);
    EXPECT_EQ(body.fields().at("code").string_value(), want.first);
    EXPECT_EQ(body.fields().at("message").string_value(), "what was wrong");
  }
}

TEST(JsonFace, AnyMessageMakesJsonQuotesControlsAndBytesThatAreNotUtf8Included) {
  const std::string message = std::string("say \"hi\"\\ then\n\t\x01 caf\xc3\xa9 ") + "\xff\xc0\xaf" +
                              " \xe2\x82" + " \xf0\x9f\x96\x90";
  const auto body = parsed(error_reply({grpc::StatusCode::INVALID_ARGUMENT, message}).body);
  EXPECT_EQ(body.fields().at("message").string_value(),
            "say \"hi\"\\ then\n\t\x01 caf\xc3\xa9 \xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd \xef\xbf\xbd\xef\xbf\xbd"
            " \xf0\x9f\x96\x90");
}

TEST(Base64, RoundTripsEveryLengthAndReadsBothAlphabetsWithOrWithoutPadding) {
  std::string bytes;
  for (int n = 0; n < 40; ++n) {
    std::string back;
    ASSERT_TRUE(decode_base64(encode_base64(bytes), back)) << n;
    EXPECT_EQ(back, bytes) << n;
    bytes.push_back(static_cast<char>(n * 37 + 251));
  }
  EXPECT_EQ(encode_base64("hapticd"), "aGFwdGljZA==");  // RFC 4648's alphabet, padded
  std::string out;
  ASSERT_TRUE(decode_base64("aGFwdGljZA", out));  // unpadded
  EXPECT_EQ(out, "hapticd");
  ASSERT_TRUE(decode_base64("-_8=", out));  // URL-safe
  EXPECT_EQ(out, std::string("\xfb\xff"));
  EXPECT_FALSE(decode_base64("not base64!", out));
  EXPECT_FALSE(decode_base64("a", out));  // one character is no byte
}

}  // namespace
}  // namespace haptic::net

// Status and Result<T>: how every fallible engine call reports failure.
// Errors are values, not exceptions, so callers decide what a failure means
// (skip a chunk, abort an import, print one line and exit).
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace vxr {

enum class ErrorCode {
  kOk = 0,
  kInvalidArgument,  // the caller passed something malformed (bad option, bad JSON)
  kNotFound,         // a file, chunk or key does not exist
  kCorrupt,          // data failed a checksum or structural check
  kUnsupported,      // valid input we do not handle (exotic format, missing device feature)
  kIo,               // the OS refused a read/write/open
  kOutOfRange,       // a size or index beyond a limit
  kGpu,              // a Vulkan call failed
  kCancelled,        // the operation was cancelled by the caller
  kInternal,         // a bug: an invariant of ours did not hold
};

const char* error_code_name(ErrorCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status ok() { return {}; }

  bool is_ok() const { return code_ == ErrorCode::kOk; }
  explicit operator bool() const { return is_ok(); }
  ErrorCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "<code>: <message>", or "ok".
  std::string to_string() const;

 private:
  ErrorCode code_ = ErrorCode::kOk;
  std::string message_;
};

inline Status invalid_argument(std::string m) { return {ErrorCode::kInvalidArgument, std::move(m)}; }
inline Status not_found(std::string m) { return {ErrorCode::kNotFound, std::move(m)}; }
inline Status corrupt(std::string m) { return {ErrorCode::kCorrupt, std::move(m)}; }
inline Status unsupported(std::string m) { return {ErrorCode::kUnsupported, std::move(m)}; }
inline Status io_error(std::string m) { return {ErrorCode::kIo, std::move(m)}; }
inline Status out_of_range(std::string m) { return {ErrorCode::kOutOfRange, std::move(m)}; }
inline Status gpu_error(std::string m) { return {ErrorCode::kGpu, std::move(m)}; }
inline Status internal_error(std::string m) { return {ErrorCode::kInternal, std::move(m)}; }

// A value or the Status that explains why there is none.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}
  Result(Status status) : v_(std::move(status)) { assert(!std::get<Status>(v_).is_ok()); }

  bool is_ok() const { return std::holds_alternative<T>(v_); }
  explicit operator bool() const { return is_ok(); }

  const Status& status() const {
    static const Status kOk;
    return is_ok() ? kOk : std::get<Status>(v_);
  }
  T& value() & { return std::get<T>(v_); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> v_;
};

}  // namespace vxr

// Early-return helpers: keep call sites to one line.
#define VXR_CONCAT_INNER(a, b) a##b
#define VXR_CONCAT(a, b) VXR_CONCAT_INNER(a, b)

#define VXR_RETURN_IF_ERROR(expr)            \
  do {                                       \
    ::vxr::Status vxr_status_ = (expr);      \
    if (!vxr_status_.is_ok()) return vxr_status_; \
  } while (0)

#define VXR_ASSIGN_OR_RETURN_IMPL(tmp, lhs, expr) \
  auto tmp = (expr);                              \
  if (!tmp.is_ok()) return tmp.status();          \
  lhs = std::move(tmp).value()

#define VXR_ASSIGN_OR_RETURN(lhs, expr) \
  VXR_ASSIGN_OR_RETURN_IMPL(VXR_CONCAT(vxr_result_, __LINE__), lhs, expr)

#pragma once
/// \file line_index.hpp
/// Lines of the values of a JSON text by JSON pointer (RFC 6901), so that errors found after
/// parsing can name the line of the value they are about. Memory is linear in the text size:
/// about 20 bytes per JSON value plus the bytes of the object keys (no per-value pointer string,
/// which would grow with depth × key length).

#include <cstdint>
#include <string>
#include <vector>

namespace incise::scene {

/// Tree of the values of one JSON text, each with its line. Built by the scene parser in one
/// pass over the text (values in document order); queried by JSON pointer.
class LineIndex {
 public:
  /// Id of a value; kNone for "no value".
  using Id = std::int32_t;
  static constexpr Id kNone = -1;

  /// True when no value has been added (a spec made in code).
  bool empty() const { return nodes_.empty(); }
  /// Number of values.
  std::size_t size() const { return nodes_.size(); }

  /// Adds a value at `line` (1-based) below `parent` (kNone for the root, which must be the
  /// first value added): an element of the array `parent` (its next index) when `key` is null,
  /// else the member `*key` of the object `parent`. Returns its id. Values must be added in
  /// document order (a parent before its children, siblings in order).
  Id add(Id parent, long line, const std::string* key = nullptr);

  /// The value at `pointer` ("" is the root, "/a/0/b~1c"), or kNone when there is none.
  Id find(const std::string& pointer) const;
  /// True when `pointer` names a value.
  bool contains(const std::string& pointer) const { return find(pointer) != kNone; }
  /// Line of the value at `pointer` (for an object member: the line of its key), or of its
  /// nearest ancestor that exists; 0 when the index is empty.
  long line(const std::string& pointer) const;

 private:
  struct Node {
    std::int32_t line;
    Id first_child = kNone;
    Id last_child = kNone;
    Id next_sibling = kNone;
    std::uint32_t key_begin = 0;  ///< object members: the key is keys_[key_begin, key_end)
    std::uint32_t key_end = 0;
  };
  /// Child of `node` named by the unescaped pointer token `token`, or kNone.
  Id child(Id node, const std::string& token) const;
  std::vector<Node> nodes_;
  std::vector<bool> is_member_;  ///< node was added with a key
  std::string keys_;             ///< every member key, concatenated
};

}  // namespace incise::scene

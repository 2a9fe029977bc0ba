#include <incise/core/error.hpp>
#include <incise/scene/line_index.hpp>

#include <limits>

namespace incise::scene {

LineIndex::Id LineIndex::add(Id parent, long line, const std::string* key) {
  INCISE_CHECK(nodes_.size() < static_cast<std::size_t>(std::numeric_limits<Id>::max()) &&
                   line >= 1 && line <= std::numeric_limits<std::int32_t>::max(),
               "LineIndex::add: too many values or line out of range");
  INCISE_CHECK(parent == kNone ? nodes_.empty()
                               : parent >= 0 && static_cast<std::size_t>(parent) < nodes_.size(),
               "LineIndex::add: the root must come first, and parents before children");
  const Id id = static_cast<Id>(nodes_.size());
  Node n;
  n.line = static_cast<std::int32_t>(line);
  if (key) {
    INCISE_CHECK(keys_.size() + key->size() <= std::numeric_limits<std::uint32_t>::max(),
                 "LineIndex::add: keys longer than 4 GiB in all");
    n.key_begin = static_cast<std::uint32_t>(keys_.size());
    keys_ += *key;
    n.key_end = static_cast<std::uint32_t>(keys_.size());
  }
  nodes_.push_back(n);
  is_member_.push_back(key != nullptr);
  if (parent != kNone) {
    Node& p = nodes_[static_cast<std::size_t>(parent)];
    if (p.last_child == kNone)
      p.first_child = id;
    else
      nodes_[static_cast<std::size_t>(p.last_child)].next_sibling = id;
    p.last_child = id;
  }
  return id;
}

LineIndex::Id LineIndex::child(Id node, const std::string& token) const {
  const Node& p = nodes_[static_cast<std::size_t>(node)];
  if (p.first_child == kNone) return kNone;
  if (is_member_[static_cast<std::size_t>(p.first_child)]) {
    // Object: the member with this key (the first one, should a key repeat).
    for (Id c = p.first_child; c != kNone; c = nodes_[static_cast<std::size_t>(c)].next_sibling) {
      const Node& n = nodes_[static_cast<std::size_t>(c)];
      if (token.compare(0, std::string::npos, keys_, n.key_begin, n.key_end - n.key_begin) == 0)
        return c;
    }
    return kNone;
  }
  // Array: the token is a decimal index without leading zeros (RFC 6901).
  if (token.empty() || token.size() > 9 || (token.size() > 1 && token[0] == '0')) return kNone;
  long index = 0;
  for (char ch : token) {
    if (ch < '0' || ch > '9') return kNone;
    index = 10 * index + (ch - '0');
  }
  Id c = p.first_child;
  for (; c != kNone && index > 0; --index) c = nodes_[static_cast<std::size_t>(c)].next_sibling;
  return c;
}

namespace {

// Splits a JSON pointer into its unescaped tokens ("~1" → '/', "~0" → '~'); false when it does
// not start with '/' (and is not "").
bool pointer_tokens(const std::string& pointer, std::vector<std::string>& tokens) {
  tokens.clear();
  if (pointer.empty()) return true;
  if (pointer[0] != '/') return false;
  std::string t;
  for (std::size_t i = 1; i <= pointer.size(); ++i) {
    if (i == pointer.size() || pointer[i] == '/') {
      tokens.push_back(t);
      t.clear();
    } else if (pointer[i] == '~' && i + 1 < pointer.size() &&
               (pointer[i + 1] == '0' || pointer[i + 1] == '1')) {
      t += pointer[++i] == '0' ? '~' : '/';
    } else {
      t += pointer[i];
    }
  }
  return true;
}

}  // namespace

LineIndex::Id LineIndex::find(const std::string& pointer) const {
  std::vector<std::string> tokens;
  if (nodes_.empty() || !pointer_tokens(pointer, tokens)) return kNone;
  Id node = 0;
  for (const std::string& t : tokens) {
    node = child(node, t);
    if (node == kNone) return kNone;
  }
  return node;
}

long LineIndex::line(const std::string& pointer) const {
  std::vector<std::string> tokens;
  if (nodes_.empty()) return 0;
  if (!pointer_tokens(pointer, tokens)) return nodes_[0].line;
  Id node = 0;
  for (const std::string& t : tokens) {
    const Id c = child(node, t);
    if (c == kNone) break;
    node = c;
  }
  return nodes_[static_cast<std::size_t>(node)].line;
}

}  // namespace incise::scene

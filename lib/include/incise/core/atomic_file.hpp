#pragma once
/// \file atomic_file.hpp
/// Files written so that a reader never sees a half-written one: the content goes to
/// `<path>.tmp`, which is then renamed to `path` (parent folders are created first).

#include <functional>
#include <string>

namespace incise {

/// Calls `write(tmp_path)` to write the file at `tmp_path` = path + ".tmp", then renames it to
/// `path`. Exceptions of `write` propagate (the rename is not done); the rename and folder
/// creation throw std::filesystem::filesystem_error.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write);

/// write_atomically() with `text` as the content. Throws Error when the temporary file cannot be
/// written.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace incise

// ImageBlocks on the wire and on disk. A worker's task result and the master's film checkpoints are
// blocks of doubles that must arrive bit for bit (merging in task order then reproduces the embedded
// render exactly), so the encoding is lossless: a small header, then, compressed with zstd, a mask of the
// values whose bits are not all zero and those values byte-shuffled (all first bytes of the doubles, then
// all second bytes, ...). Shuffling groups the slowly varying sign/exponent bytes, which is what lets zstd
// shrink doubles at all; the mask spares it the zeros, half of a Markov-chain task's film at 1024².
// A Tiles block (a chain task's film, image/splat_tiles.h) travels as the list of its tiles present and
// their values alone: a task's result is then the size of what it deposited, not of the crop window.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "image/film.h"

namespace pf::farm {

std::string encodeBlock(const ImageBlock &block, int zstdLevel = 1);

// Decodes into `block`, which must have the layout (offset, size, border) and the storage (Dense or Tiles)
// the data was encoded with; throws FarmError naming the problem if it does not, if the data is corrupt
// (for tiles also: a tile out of range, listed twice or out of order), or if any value is not finite (a
// renderer never produces those, so they mean a broken or hostile sender). A Tiles block ends up with
// exactly the tiles listed.
void decodeBlock(std::string_view data, ImageBlock &block);
// The same, decompressing into `scratch` (grown as needed, never shrunk), so that a caller that decodes
// many blocks allocates and clears that memory once: the master, which decodes every result.
void decodeBlock(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch);

}  // namespace pf::farm

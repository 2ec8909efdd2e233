// Why: frames travel from GL (rows bottom-up) to the video encoder; handing them over in GL's
// own order saves a copy per frame (swscale flips for free with a negative stride).
#pragma once

namespace springy::render {

// Row order of an RGBA8 frame: TopDown = row 0 is the top of the image (PNG, Image);
// BottomUp = OpenGL's order, row 0 is the bottom.
enum class RowOrder { TopDown, BottomUp };

}  // namespace springy::render

// The report's style and its 3D viewer (three.js and app/report/viewer.js, bundled by esbuild at
// build time: app/CMakeLists.txt), in the program: app/report.cpp writes them into each report.
// The paths come from the build (SPRINGY_REPORT_VIEWER, SPRINGY_REPORT_STYLE).
#define SPRINGY_EMBED(name, file)                                                   \
  ".global " #name "\n.hidden " #name "\n.type " #name ", @object\n.balign 16\n" #name \
  ":\n.incbin \"" file "\"\n.global " #name "_end\n.hidden " #name "_end\n" #name "_end:\n.byte 0\n"

__asm__(".section .rodata\n" SPRINGY_EMBED(springy_report_viewer, SPRINGY_REPORT_VIEWER)
            SPRINGY_EMBED(springy_report_style, SPRINGY_REPORT_STYLE) ".previous\n");

#pragma once
// A 1 KB Collada file whose nodes instance each other: Assimp 5.2 follows the instances until
// its stack overflows (SIGSEGV). load_mesh() must survive it (the import runs in a helper).

#include <string>

namespace esf::test {

inline std::string recursive_collada() {
    return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_nodes>
    <node id="a" name="a"><instance_node url="#b"/></node>
    <node id="b" name="b"><instance_node url="#a"/></node>
  </library_nodes>
  <library_visual_scenes>
    <visual_scene id="scene" name="scene">
      <node id="root" name="root"><instance_node url="#a"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}

}  // namespace esf::test

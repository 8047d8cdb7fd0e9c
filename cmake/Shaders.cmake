# Compiles every shaders/*.comp to SPIR-V with glslangValidator at build time and embeds the words
# in a header <name>_spv.hpp in the build directory (never committed as SPIR-V):
#   namespace shapematch::spv { inline constexpr uint32_t <name>[] = {...}; }
# `target` becomes an INTERFACE library whose include directory holds those headers.
function(shapematch_embed_shaders target shader_dir)
  file(GLOB shader_sources CONFIGURE_DEPENDS ${shader_dir}/*.comp)
  set(out_dir ${CMAKE_BINARY_DIR}/generated/shaders)
  file(MAKE_DIRECTORY ${out_dir})
  set(headers "")
  foreach(src ${shader_sources})
    get_filename_component(name ${src} NAME_WE)
    set(spv ${out_dir}/${name}.spv)
    set(hdr ${out_dir}/${name}_spv.hpp)
    add_custom_command(
      OUTPUT ${hdr}
      COMMAND ${GLSLANG_VALIDATOR} --target-env vulkan1.1 -Os -o ${spv} ${src}
      COMMAND ${CMAKE_COMMAND} -DSPV=${spv} -DHDR=${hdr} -DNAME=${name}
              -P ${CMAKE_SOURCE_DIR}/cmake/SpirvToHeader.cmake
      DEPENDS ${src} ${CMAKE_SOURCE_DIR}/cmake/SpirvToHeader.cmake
      COMMENT "glslang: ${name}.comp"
      VERBATIM)
    list(APPEND headers ${hdr})
  endforeach()
  add_custom_target(${target}_compile DEPENDS ${headers})
  add_library(${target} INTERFACE)
  target_include_directories(${target} INTERFACE ${out_dir})
  add_dependencies(${target} ${target}_compile)
endfunction()

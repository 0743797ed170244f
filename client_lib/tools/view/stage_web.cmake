# Run at build time (target telegrasp-view-web): stages into OUT (share/telegrasp/view of the
# build tree) what telegrasp-view serves from its npm packages in WEB_DIR/node_modules: three.js's
# module build, OrbitControls and GLTFLoader, the generic hand glTF models of
# @webxr-input-profiles/assets, and the foxglove.* JSON schemas generated from @foxglove/schemas.
# Without node_modules it warns and stages nothing; telegrasp-view then says what is missing.
set(modules ${WEB_DIR}/node_modules)
set(hands ${modules}/@webxr-input-profiles/assets)
if(NOT EXISTS ${modules}/three/build/three.module.js OR NOT EXISTS ${modules}/@foxglove/schemas/package.json
   OR NOT EXISTS ${hands}/dist/profiles/generic-hand/right.glb)
  message(WARNING "telegrasp-view: ${modules} lacks three, @foxglove/schemas or @webxr-input-profiles/assets: run deploy/install-deps.sh "
                  "(npm ci in client_lib/tools/view/web), then build again")
  return()
endif()
foreach(file build/three.module.js build/three.core.js examples/jsm/controls/OrbitControls.js
             examples/jsm/loaders/GLTFLoader.js examples/jsm/utils/BufferGeometryUtils.js
             examples/jsm/utils/SkeletonUtils.js LICENSE)
  get_filename_component(dir ${OUT}/vendor/three/${file} DIRECTORY)
  file(MAKE_DIRECTORY ${dir})
  file(COPY_FILE ${modules}/three/${file} ${OUT}/vendor/three/${file} ONLY_IF_DIFFERENT)
endforeach()
file(MAKE_DIRECTORY ${OUT}/vendor/generic-hand)
foreach(file dist/profiles/generic-hand/left.glb dist/profiles/generic-hand/right.glb LICENSE.md)
  get_filename_component(name ${file} NAME)
  file(COPY_FILE ${hands}/${file} ${OUT}/vendor/generic-hand/${name} ONLY_IF_DIFFERENT)
endforeach()
set(stamp ${OUT}/schemas/foxglove.SceneUpdate.json)
if(NOT EXISTS ${stamp} OR ${WEB_DIR}/package-lock.json IS_NEWER_THAN ${stamp}
   OR ${modules}/@foxglove/schemas/package.json IS_NEWER_THAN ${stamp})
  if(NOT NODE)
    message(WARNING "telegrasp-view: node not found, cannot generate the foxglove schemas: run deploy/install-deps.sh")
    return()
  endif()
  execute_process(COMMAND ${NODE} ${WEB_DIR}/gen_schemas.cjs ${OUT}/schemas RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "telegrasp-view: generating the foxglove schemas failed (${status})")
  endif()
endif()

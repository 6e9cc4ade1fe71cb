# cmake -DDYNAHAND=... -DWORK_DIR=... -DARM_MODEL=... -P BadInput.cmake
# Bad input to the commands (docs/reliability.md): one line naming the option or file and exit
# code 2; outputs written whole under their name or not at all.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(W ${WORK_DIR})

# expect(CODE REGEX ARGS...): runs dynahand ARGS, checks its exit code and that stderr matches.
function(expect code regex)
  execute_process(COMMAND ${DYNAHAND} ${ARGN} RESULT_VARIABLE rc ERROR_VARIABLE err
                  OUTPUT_QUIET TIMEOUT 120)
  if(NOT rc STREQUAL "${code}" OR NOT err MATCHES "${regex}")
    message(FATAL_ERROR "dynahand ${ARGN}: exit ${rc} (expected ${code}), stderr: ${err}")
  endif()
endfunction()
function(expect_missing path)
  if(EXISTS ${path})
    message(FATAL_ERROR "${path} exists but should not")
  endif()
endfunction()

expect(0 "" synth --motion wave --frames 3 --out ${W}/clip)
expect(0 "" track ${W}/clip --out ${W}/poses.jsonl)

# 1. NaN and infinities in any floating-point option: refused, naming the option.
expect(2 "--proportion-spread: must be a finite number" detector data --count 1 --proportion-spread nan -o ${W}/d.bin)
expect(2 "--proportion-spread: must be a finite number" detector eval --proportion-spread nan)
expect(2 "--minutes: must be a finite number" bench --suite soak --minutes nan)
expect(2 "--hand-length: must be a finite number" track ${W}/clip --hand-length nan)
expect(2 "--hand-width: must be a finite number" track ${W}/clip --hand-width nan)
expect(2 "--length: must be a finite number" model --length nan)
expect(2 "--width: must be a finite number" model --width nan)
expect(2 "--fps: must be a finite number" eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses.jsonl --fps nan)
expect(2 "--lost-mm: must be a finite number" eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses.jsonl --lost-mm nan)
expect(2 "--fps: must be a finite number" render ${W}/poses.jsonl ${W}/clip --out ${W}/r --fps nan)
expect(2 "--side-angle: must be a finite number" render ${W}/poses.jsonl ${W}/clip --out ${W}/r --side-angle nan)
expect(2 "--eye: must be a finite number" play scene.json ${W}/clip --eye nan 0 0)
expect(2 "--fps: must be a finite number" play scene.json ${W}/clip --fps nan)
expect(2 "--seed: must be a whole number >= 0" synth --seed -1 --out ${W}/s1)
expect_missing(${W}/r)

# 3. Bad input is exit 2, naming the file.
expect(2 "three_link_arm.json: not a hand model" track ${W}/clip --model ${ARM_MODEL})
file(WRITE ${W}/trunc.json "{\"format\": \"dynahand-model\", ")
expect(2 "trunc.json: not valid JSON" model --check ${W}/trunc.json)
expect(2 "trunc.json: not valid JSON" model --from-intel ${W}/trunc.json)
expect(2 "already holds a sequence" synth --motion wave --frames 3 --out ${W}/clip)
expect(2 "--host: not an IP address: 999.1.1.1" serve ${W}/clip --host 999.1.1.1 --port 0)
expect(2 "unknown back end 'nosuch'" track camera:nosuch)
file(WRITE ${W}/afile "x")
expect(2 "afile/x.bvh: cannot write" track ${W}/clip --bvh ${W}/afile/x.bvh)

# A depth frame that does not decode: exit 2, and no partial output under its name.
expect(0 "" synth --motion wave --frames 3 --out ${W}/bad)
file(WRITE ${W}/bad/depth/000001.png "not a png")
expect(2 "bad/depth/000001.png: not a PNG file" track ${W}/bad --out ${W}/bad.jsonl --bvh ${W}/bad.bvh)
expect_missing(${W}/bad.jsonl)
expect_missing(${W}/bad.bvh)
expect(2 "bad/depth/000001.png: not a PNG file" render ${W}/poses.jsonl ${W}/bad --out ${W}/bad.mp4)
expect_missing(${W}/bad.mp4)
expect_missing(${W}/bad.part.mp4)

# 2. Outputs: whole under their name, no temporary left behind.
expect(0 "" render ${W}/poses.jsonl ${W}/clip --out ${W}/v.mp4)
if(NOT EXISTS ${W}/v.mp4 OR EXISTS ${W}/v.part.mp4)
  message(FATAL_ERROR "render --out v.mp4: no v.mp4, or v.part.mp4 left")
endif()
expect(0 "" model -o ${W}/m.json)
expect(0 "" eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses.jsonl --out ${W}/rep)
foreach(f m.json rep/report.md rep/error_over_time.svg rep/success_curve.svg)
  if(NOT EXISTS ${W}/${f} OR EXISTS ${W}/${f}.part)
    message(FATAL_ERROR "${f}: missing, or ${f}.part left")
  endif()
endforeach()
expect_missing(${W}/clip.part)
# A file that cannot be written in full (its temporary name leads to /dev/full): an error
# naming the file, and nothing under the final name.
if(EXISTS /dev/full)
  file(CREATE_LINK /dev/full ${W}/full.json.part SYMBOLIC)
  expect(1 "full.json: write failed" model -o ${W}/full.json)
  expect_missing(${W}/full.json)
  file(MAKE_DIRECTORY ${W}/rep2)
  file(CREATE_LINK /dev/full ${W}/rep2/error_over_time.svg.part SYMBOLIC)
  expect(1 "rep2/error_over_time.svg: write failed"
         eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses.jsonl --out ${W}/rep2)
  expect_missing(${W}/rep2/error_over_time.svg)
  execute_process(COMMAND ${DYNAHAND} model OUTPUT_FILE /dev/full RESULT_VARIABLE rc
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "standard output: write failed")
    message(FATAL_ERROR "model > /dev/full: exit ${rc}, stderr: ${err}")
  endif()
endif()
# synth writes OUT.part and moves it into OUT at the end; a leftover OUT.part is refused.
file(MAKE_DIRECTORY ${W}/s2.part)
file(WRITE ${W}/s2.part/camera.json "{}")
expect(2 "s2.part: left by a synth run that did not finish" synth --motion wave --frames 3 --out ${W}/s2)
expect_missing(${W}/s2)

# 4. eval --side of a hand the prediction does not have; a newer tracked-pose version.
expect(2 "--side left: .*poses.jsonl has no tracked left hand"
       eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses.jsonl --side left)
file(READ ${W}/poses.jsonl poses)
string(REPLACE "\"version\":1" "\"version\":2" poses2 "${poses}")
if(poses2 STREQUAL poses)
  message(FATAL_ERROR "poses.jsonl has no \"version\":1 field")
endif()
file(WRITE ${W}/poses_v2.jsonl "${poses2}")
expect(2 "poses_v2.jsonl:1: \"version\" 2 is newer"
       eval --gt ${W}/clip/groundtruth.jsonl --pred ${W}/poses_v2.jsonl)
expect(2 "poses_v2.jsonl:1: \"version\" 2 is newer" render ${W}/poses_v2.jsonl ${W}/clip --out ${W}/r2)

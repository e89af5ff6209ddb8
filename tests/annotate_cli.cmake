# `vxr annotate` and `vxr cards` as a script would use them: one store, one
# workflow, every step's exit code and output checked.
#   -DVXR=path -DDIR=scratch folder -DTESTDATA=../shared/testdata -DSRC=source tree
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})
set(S ${DIR}/store)

# step(<expected rc> <stdout regex> <stderr regex> args...)
function(step rc out_re err_re)
  execute_process(COMMAND ${VXR} ${ARGN} RESULT_VARIABLE got OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("$ vxr ${ARGN}\n${out}${err}")
  if(NOT got EQUAL rc)
    message(FATAL_ERROR "expected exit ${rc}, got ${got}")
  endif()
  if(NOT out MATCHES "${out_re}")
    message(FATAL_ERROR "stdout does not match '${out_re}'")
  endif()
  if(NOT err MATCHES "${err_re}")
    message(FATAL_ERROR "stderr does not match '${err_re}'")
  endif()
endfunction()

step(2 "^$" "no annotation store here" annotate list ${DIR}/missing)
step(0 "store: annotation store, schema 1, voxel size 0.5,0.5,2 um" "^$" annotate init ${S} --voxel-size 0.5,0.5,2)
step(0 "^marker 1\n$" "^$" annotate add-marker ${S} --pos 1,2,3 --class neuron --color 1,0,0)
step(0 "^marker 2\n$" "^$" annotate add-marker ${S} --pos 4,5,6 --class neuron --t 1)
step(0 "^marker 3\n$" "^$" annotate add-marker ${S} --pos 40,5,6 --class glia)
step(2 "^$" "--pos '1,2': give three numbers" annotate add-marker ${S} --pos 1,2)
step(0 "^glia\t1\nneuron\t2\ntotal\t3\n$" "^$" annotate count ${S})
step(0 "^neuron\t1\ntotal\t1\n$" "^$" annotate count ${S} --t 1)
# (3, 4, 1) voxels of 0.5 x 0.5 x 2 um = (1.5, 2, 2) um -> sqrt(10.25)
step(0 "^measurement 1: 3.20156 um\n$" "^$" annotate measure ${S} --from 0,0,0 --to 3,4,1 --label gap)
step(0 "^track 1\n$" "^$" annotate add-track ${S} --markers 2,1 --name cellA)
step(2 "^$" "both at timepoint 0; a track holds one marker per timepoint" annotate add-track ${S} --markers 1,3)
step(0 "^roi 1\n$" "^$" annotate add-roi ${S} --min 0,0,0 --max 10,10,10 --name box)
step(0 "^marker 1 neuron 1,2,3 t=0\nmarker 2 neuron 4,5,6 t=1\nmeasurement 1 gap 3.20156 um\ntrack 1 cellA\n$" "^$"
     annotate query ${S} --roi 1)
step(0 "^marker 2 neuron 4,5,6 t=1\ntrack 1 cellA\n$" "^$" annotate query ${S} --min 0,0,0 --max 10,10,10 --t 1)
step(0 "^skeleton 1: 8 nodes from .*Neuron_missing_ids.swc \\(3 warnings\\)\n$"
     "warning: [^\n]*Neuron_missing_ids.swc:[0-9]+: sample 8 names parent 7, which is not in the file"
     annotate import-swc ${S} ${TESTDATA}/swc-malformed/Neuron_missing_ids.swc)
step(1 "^$" "^vxr: [^\n]*repeated_id.swc:6: sample id 4 is repeated \\(first defined on line 5\\); make ids unique\n$"
     annotate import-swc ${S} ${TESTDATA}/swc-malformed/repeated_id.swc)
# Tracing edits on that skeleton: 1 root; 2<-1, 3<-2, 4<-3, 5<-3, 6<-1; 8 and 9 roots.
step(0 "^node 10\n$" "^$" annotate edit-skeleton ${S} --skeleton 1 --add 2,2,2 --parent 9 --radius 0.5 --type 3)
step(0 "^ok\n$" "^$" annotate edit-skeleton ${S} --skeleton 1 --move 10 --to 3,3,3)
step(0 "^ok\n$" "^$" annotate edit-skeleton ${S} --skeleton 1 --reparent 8 --parent 6)
step(2 "^$" "cannot attach node 1 under 3: that node is in its own subtree \\(a cycle\\)"
     annotate edit-skeleton ${S} --skeleton 1 --reparent 1 --parent 3)
step(2 "^$" "give exactly one of" annotate edit-skeleton ${S} --skeleton 1 --delete 4 --split 2)
step(0 "^skeleton 2\n$" "^$" annotate edit-skeleton ${S} --skeleton 1 --split 2)
step(0 "^merged 4 nodes into skeleton 1; node 3 is now 12\n$" "^$"
     annotate edit-skeleton ${S} --skeleton 1 --merge-from 2 --from-node 3 --parent 9)
step(0 "^ok\n$" "^$" annotate edit-skeleton ${S} --skeleton 1 --delete 6)
step(2 "^$" "no node 6" annotate edit-skeleton ${S} --skeleton 1 --delete 6)
step(0 "1 skeletons.*skeleton 1 Neuron_missing_ids.swc: 8 nodes, 2 roots" "^$" annotate list ${S})
step(0 "n.swc: 8 samples" "^$" annotate export-swc ${S} --skeleton 1 -o ${DIR}/n.swc)
file(READ ${DIR}/n.swc swc)
# Parents first, micrometres: root 1, then 8 (under 6, which was deleted, so now under 1), root 9, the added node
# (voxel 3,3,3 = 1.5,1.5,6 um), then the merged tree re-rooted at its old node 3.
if(NOT swc MATCHES "\n1 1 0 0 0 1 -1\n2 2 6 -4 0 0 1\n3 2 -5 -4 0 0 -1\n4 3 1.5 1.5 6 0.5 3\n5 3 0 5 0 1 3\n")
  message(FATAL_ERROR "exported SWC does not hold the edited tree:\n${swc}")
endif()
step(2 "^$" "is inside the input folder" annotate export-swc ${S} --skeleton 1 -o ${S}/CURRENT)
step(2 "^$" "no skeleton 9" annotate export-swc ${S} --skeleton 9 -o ${DIR}/x.swc)
step(0 "^class,count\nglia,1\nneuron,2\n$" "^$" annotate export-csv ${S} --what counts)
step(0 "tracks.csv: tracks" "^$" annotate export-csv ${S} --what tracks -o ${DIR}/tracks.csv)
file(READ ${DIR}/tracks.csv csv)
if(NOT csv STREQUAL "track,name,step,marker,timepoint,x,y,z,step_length_um\n1,cellA,0,1,0,1,2,3,\n1,cellA,1,2,1,4,5,6,6.363961030678928\n")
  message(FATAL_ERROR "tracks.csv:\n${csv}")
endif()
step(0 "3 markers, 1 measurements, 1 skeletons, 1 tracks, 1 ROIs, 0 cards, 0 meshes\n.*skeleton 1 Neuron_missing_ids.swc: 8 nodes, 2 roots"
     "^$" annotate list ${S})

step(0 "^card 1\n$" "^$" cards add ${S} --title "Spine cluster" --note "Dense spines near the soma"
     --scene ${SRC}/tests/data/card_scene.json --snapshot ${SRC}/golden_images/model_ea.png)
step(0 "^card 2\n$" "^$" cards add ${S} --note "axon bouton" --snapshot-path ${SRC}/golden_images/model_ea.png)
step(2 "^$" "card snapshot is not a PNG file" cards add ${S} --note x --snapshot ${SRC}/tests/data/card_scene.json)
step(0 "^1\t[0-9-]+ [0-9:]+ UTC\tSpine cluster  \\[snapshot\\]\n2\t[^\n]*\taxon bouton  \\[snapshot\\]\n$" "^$" cards list ${S})
step(0 "snapshot: [^\n]*golden_images/model_ea.png\n" "^$" cards show ${S} 2)
step(2 "^$" "--snapshot-path /nonexistent.png: no such file" cards add ${S} --snapshot-path /nonexistent.png)
step(0 "^1\t[^\n]*Spine cluster[^\n]*\n$" "^$" cards search ${S} SPINES soma)
step(1 "^$" "no card matches 'dendrite'" cards search ${S} dendrite)
step(0 "title: Spine cluster\n.*note:\nDense spines near the soma\nscene:\n.*\"model\": \"mip\"" "^$" cards show ${S} 1)
step(0 "card-1.png\n.*card-1.json\n$" "^$" cards export ${S} 1 -o ${DIR}/cards)
file(SHA256 ${DIR}/cards/card-1.png got)
file(SHA256 ${SRC}/golden_images/model_ea.png want)
if(NOT got STREQUAL want)
  message(FATAL_ERROR "exported snapshot differs from the PNG that was stored")
endif()
file(READ ${DIR}/cards/card-1.json card)
if(NOT card MATCHES "\"note\": \"Dense spines near the soma\"" OR NOT card MATCHES "\"volume\": \"head.vxc\"")
  message(FATAL_ERROR "card-1.json:\n${card}")
endif()

# The analysis tools from a script: counting, a measurement, a traced branch.
set(T ${DIR}/tools_store)
step(0 "voxel size 0.5,0.5,2 um" "^$" annotate init ${T} --voxel-size 0.5,0.5,2)
file(WRITE ${DIR}/tools.json [=[{"events": [
  {"tool": "count", "class": "nucleus"}, {"press": [10, 10, 1]}, {"press": [20, 10, 1]},
  {"tool": "measure"}, {"press": [0, 0, 0]}, {"move": [2, 0, 0]}, {"release": [0, 0, 1]},
  {"tool": "trace"}, {"press": [5, 5, 1]}, {"press": [5, 9, 1]}]}]=])
step(0 "event 1: marker 1 \\(nucleus\\) at \\(10, 10, 1\\)\n.*event 6: measurement 1: 2 um\n.*event 9: node 2 of skeleton 1 below node 1\ncounts at the last timepoint: nucleus 2\n$"
     "^$" annotate play ${T} ${DIR}/tools.json)
step(0 "2 markers, 1 measurements, 1 skeletons" "^$" annotate list ${T})
file(WRITE ${DIR}/bad_tools.json [=[{"events": [{"tool": "count"}, {"prss": [1, 2, 3]}]}]=])
step(2 "^$" "bad_tools.json: event 1: unknown key \"prss\"" annotate play ${T} ${DIR}/bad_tools.json)

# A segmented surface imported as meshes, one per OBJ part.
step(0 "^mesh 1 'Icosphere_Icosphere.001': 1280 triangles\n$" "^$" annotate import-obj ${T} ${TESTDATA}/obj/ico4.obj --opacity 0.5)
step(0 "1 meshes\n.*mesh 1 Icosphere_Icosphere.001: 1280 triangles\n" "^$" annotate list ${T})
step(2 "^$" "missing.obj: no such file" annotate import-obj ${T} ${DIR}/missing.obj)

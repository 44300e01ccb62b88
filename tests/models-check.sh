#!/bin/sh
# Checks of the shipped models: check_urdf on every URDF, forward kinematics of
# the authored PR2 and Pepper against the reference models, scene geometry,
# that the generators reproduce the committed files, and that the checks
# reject broken input.  Prints "N passed, N failed"; exits 1 on any failure.
root=$(cd "$(dirname "$0")/.." && pwd)
tools="$root/tools/models"
py=/usr/bin/python3
export PYTHONDONTWRITEBYTECODE=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
ok()   { passed=$((passed + 1)); echo "ok   $1"; }
bad()  { failed=$((failed + 1)); echo "FAIL $1"; }

urdfs="$root/robots/pr2/pr2.urdf $root/robots/pepper/pepper.urdf $root/resources/iai_kitchen.urdf $root/resources/dm_shelves.urdf"
if command -v check_urdf >/dev/null 2>&1; then
  for u in $urdfs; do
    if check_urdf "$u" >"$tmp/check.log" 2>&1 && grep -q "Successfully Parsed" "$tmp/check.log"; then
      ok "check_urdf ${u#$root/}"
    else
      bad "check_urdf ${u#$root/}"; cat "$tmp/check.log"
    fi
  done
  printf '<robot name="broken"><link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="missing"/></joint></robot>\n' >"$tmp/broken.urdf"
  if check_urdf "$tmp/broken.urdf" >/dev/null 2>&1; then bad "check_urdf rejects a broken URDF"; else ok "check_urdf rejects a broken URDF"; fi
else
  echo "skip check_urdf (liburdfdom-tools not installed)"
fi

if $py "$tools/fk_check.py"; then ok "fk_check"; else bad "fk_check"; fi

# A PR2 whose wrist is 2 mm off must fail the FK comparison.
if [ -f "$root/../shared/models/pr2_description/urdf/pr2.urdf" ]; then
  sed 's|<origin xyz="0.321 0 0" rpy="0 0 0"/>|<origin xyz="0.323 0 0" rpy="0 0 0"/>|' \
    "$root/robots/pr2/pr2.urdf" >"$tmp/pr2-off.urdf"
  if cmp -s "$tmp/pr2-off.urdf" "$root/robots/pr2/pr2.urdf"; then
    bad "fk_check negative test could not perturb the PR2"
  elif $py "$tools/fk_check.py" --samples 50 --authored "$tmp/pr2-off.urdf" \
        --reference "$root/../shared/models/pr2_description/urdf/pr2.urdf" >/dev/null; then
    bad "fk_check rejects a PR2 with a 2 mm error"
  else
    ok "fk_check rejects a PR2 with a 2 mm error"
  fi
fi

if $py "$tools/check_scene.py"; then ok "check_scene"; else bad "check_scene"; fi

# The generators reproduce the committed files byte for byte.
mkdir -p "$tmp/gen/robots/pr2" "$tmp/gen/robots/pepper" "$tmp/gen/resources/meshes"
if "$tools/generate-all" "$tmp/gen" >/dev/null; then
  diffs=0
  for f in robots/pr2/pr2.urdf robots/pepper/pepper.urdf resources/iai_kitchen.urdf resources/dm_shelves.urdf \
           resources/maps/kitchen.pgm resources/maps/kitchen.yaml resources/maps/shop.pgm resources/maps/shop.yaml \
           $(cd "$root" && ls resources/meshes/*.stl); do
    cmp -s "$tmp/gen/$f" "$root/$f" || { echo "  differs: $f"; diffs=$((diffs + 1)); }
  done
  if [ $diffs -eq 0 ]; then ok "generate-all reproduces the committed files"; else bad "generate-all reproduces the committed files"; fi
else
  bad "generate-all runs"
fi

# The rasteriser rejects a malformed URDF with an error instead of writing a map.
printf '<robot name="x"><link name="a"><collision><geometry><box size="1 2"/></geometry></collision></link></robot>\n' >"$tmp/bad-box.urdf"
if $py "$tools/rasterize_map.py" "$tmp/bad-box.urdf" "$tmp/bad" >"$tmp/r.log" 2>&1 || [ -f "$tmp/bad.pgm" ]; then
  bad "rasterize_map rejects a box with two sizes"
else
  grep -q "box size" "$tmp/r.log" && ok "rasterize_map rejects a box with two sizes" || bad "rasterize_map error names the bad box size"
fi

echo "$passed passed, $failed failed"
[ $failed -eq 0 ]

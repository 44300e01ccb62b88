;;;; Household location designators in the IAI kitchen: in, above, level, side, range, table
;;;; setting slots, relations to the bowl, attachments, base poses at a drawer, the restricted
;;;; area; sampled poses checked against the kitchen's boxes and map positions.

(in-package :cram-household-tests)

(in-suite household)

(defun samples (designator &optional (n 30))
  "N pose samples (map) of DESIGNATOR's merged costmap, at the centres of their cells."
  (let ((costmap (costmap:designator-costmap designator)))
    (is-true costmap "the designator has a costmap")
    (loop for s in (cut:force-ll (cut:lazy-take n (costmap:costmap-samples costmap :jitter nil)))
          collect (cl-transforms-stamped:pose-stamped->pose s))))

(defun sample-points (designator &optional (n 30))
  (mapcar #'xyz (samples designator n)))

(defun drawer (urdf-name &rest more)
  (desig:make-designator :object `((:type :drawer) (:urdf-name ,urdf-name) (:part-of :iai-kitchen)
                                   ,@more)))

(defun location (&rest properties) (desig:make-designator :location properties))

(defun link-box (link)
  "(values lo hi) of the kitchen LINK's box as (x y z) lists."
  (let ((k (kitchen)))
    (multiple-value-bind (lo hi) (btr:aabb k (btr:link-index k link))
      (values (xyz lo) (xyz hi)))))

(defun inside-xy-p (point lo hi)
  (and (<= (- (first lo) 1d-6) (first point) (+ (first hi) 1d-6))
       (<= (- (second lo) 1d-6) (second point) (+ (second hi) 1d-6))))

(defun mean (numbers) (/ (reduce #'+ numbers) (length numbers)))

(defun in-drawer-points ()
  (let ((points (sample-points (location `(:in ,(drawer :sink-area-left-upper-drawer-main))) 200)))
    (multiple-value-bind (lo hi) (link-box "sink_area_left_upper_drawer_main")
      (is (every (lambda (p) (inside-xy-p p lo hi)) points) "samples inside the drawer's box")
      (is (every (lambda (p) (< (abs (- (third p) (+ (third lo) 0.04d0))) 1d-6)) points)
          "at the bottom of the drawer's box + 0.04"))
    points))

(test in-drawer-inside-its-box-and-moving-with-it
  (with-household-kitchen ()
    (let ((closed (mean (mapcar #'first (in-drawer-points))))
          (closed-box (link-box "sink_area_left_upper_drawer_main")))
      (btr:set-robot-state-from-joints '(("sink_area_left_upper_drawer_main_joint" 0.48d0)) (kitchen))
      (is (< (abs (- (first closed-box) (first (link-box "sink_area_left_upper_drawer_main")) 0.48d0)) 1d-6)
          "the drawer's box moved 0.48 m towards -x")
      (let ((open (mean (mapcar #'first (in-drawer-points)))))
        (is (< (abs (- closed open 0.48d0)) 0.03d0)
            "the samples come 0.48 m out of the furniture with the drawer, moved ~,3f" (- closed open))))))

(test in-with-for-adds-the-object-height
  (with-household-kitchen ()
    (spawn :bowl-1 :bowl '((-3.4 0.0 0.8) (0 0 0 1)))
    (let ((points (sample-points (location `(:in ,(drawer :sink-area-left-middle-drawer-main))
                                           `(:for ,(desig:an object (type bowl) (name bowl-1)))))))
      (multiple-value-bind (lo hi) (link-box "sink_area_left_middle_drawer_main")
        (is (every (lambda (p) (< (abs (- (third p) (+ (third lo) 0.04d0 0.0502d0))) 5d-3)) points)
            "bottom + 0.04 + the bowl's origin height above its bottom (0.0502)")
        (is (every (lambda (p) (and (<= (+ (first lo) 0.08) (first p) (- (first hi) 0.08))
                                    (<= (+ (second lo) 0.08) (second p) (- (second hi) 0.08))))
                   points)
            "kept half the bowl's width from the drawer's sides")))))

(test levels-topmost-bottommost-and-the-fridge-door
  (with-household-kitchen ()
    (let ((k (kitchen)))
      (is (string= "oven_area_area_right_drawer_board_3_link"
                   (costmap:container-level-link k "oven_area_area_right_drawer_main" :topmost "test")))
      (is (string= "oven_area_area_right_drawer_board_0_link"
                   (costmap:container-level-link k "oven_area_area_right_drawer_main" :bottommost "test")))
      (is (string= "oven_area_area_right_drawer_board_1_link"
                   (costmap:container-level-link k "oven_area_area_right_drawer_main" 2 "test")))
      (is (string= "iai_fridge_door_shelf1_bottom"
                   (costmap:container-level-link k "iai_fridge_door" :bottommost "test"))
          "the fridge door's shelves hang under its block")
      (is (string= "oven_area_area_right_drawer_board_2_link"
                   (costmap:container-level-link k "oven_area_area_right_drawer_main" 2 "test" :invert t))
          "(level-invert 2): the second from the top")
      (signals error (costmap:container-level-link k "oven_area_area_right_drawer_main" 7 "test"))
      (signals error (costmap:container-level-link k "sink_area_left_upper_drawer_main" :topmost "test")))
    (let ((milk (man-int:get-object-likely-location :milk :iai-kitchen nil :table-setting)))
      (multiple-value-bind (lo hi) (link-box "iai_fridge_door_shelf1_bottom")
        (let ((points (sample-points milk)))
          (is (every (lambda (p) (inside-xy-p p lo hi)) points) "on the fridge door's lowest shelf")
          (is (every (lambda (p) (< (abs (- (third p) (third hi))) 1d-6)) points)
              "at the shelf's top, ~,3f" (third hi))
          (is (< (abs (- (third hi) 0.6325d0)) 0.002d0) "the shelf's top is at 0.6325"))))))

(test side-and-range-in-the-body-frame
  (with-household-kitchen ()
    ;; drawer frames point +x out of the furniture, towards the handle: back = handle half
    (let* ((d (drawer :sink-area-left-upper-drawer-main))
           (pose (btr:link-pose (kitchen) "sink_area_left_upper_drawer_main"))
           (ox (cl-transforms:x (cl-transforms:origin pose)))
           (points (sample-points (location `(:in ,d) '(:side :back)))))
      (is (every (lambda (p) (< (first p) ox)) points)
          "(side back) of a sink drawer: map x below the drawer origin's ~,3f (towards the room)" ox))
    (let* ((table (desig:make-designator :object '((:type :counter-top) (:urdf-name :dining-area-jokkmokk-table-main)
                                                   (:part-of :iai-kitchen))))
           (points (sample-points (location `(:on ,table) '(:side :front) '(:range 0.2)))))
      (is (every (lambda (p) (< (second p) 0.31d0)) points) "front of the table: map y < 0.31")
      (is (every (lambda (p) (< (dist-xy p '(-3.38 0.31)) 0.2001d0)) points) "within 0.2 m of its centre")
      (let ((far (sample-points (location `(:on ,table) '(:side (:front :right)) '(:range-invert 0.3)))))
        (is (every (lambda (p) (and (< (second p) 0.31d0) (> (first p) -3.38d0)
                                    (> (dist-xy p '(-3.38 0.31)) 0.3d0)))
                   far)
            "(side (front right)): y < 0.31 and map x > -3.38 (the table's -y), beyond 0.3 m"))
      (let ((yaw (yaw-of (btr:link-pose (kitchen) "dining_area_jokkmokk_table_main"))))
        (is (every (lambda (pose) (< (abs (sin (* 2 (- (yaw-of pose) yaw)))) 1d-6))
                   (samples (location `(:on ,table) '(:orientation :support-aligned)) 10))
            "(on table) (orientation support-aligned): along the table's axes")))))

;; The designator's own solutions, as a plan gets them (every generator, in order), not only
;; its costmap's samples: (side ...) is a side of the surface, not the era's arm.
(test side-and-range-hold-for-the-designators-solutions
  (with-household-kitchen ()
    (spawn :cereal-1 :breakfast-cereal '((1.4 1.5 0.9) (0 0 0 1)))
    (let* ((table (desig:make-designator :object '((:type :counter-top) (:urdf-name :dining-area-jokkmokk-table-main)
                                                   (:part-of :iai-kitchen))))
           (d (location `(:on ,table) `(:for ,(desig:an object (type breakfast-cereal)))
                        '(:range 0.2) '(:side :front)))
           (points (loop for s = d then (desig:next-solution s)
                         repeat 60 while s
                         collect (xyz (cl-transforms-stamped:pose-stamped->pose (desig:reference s))))))
      (is (= 60 (length points)) "60 solutions")
      ;; the solutions are placed anywhere in their cell: half a cell (0.025 m) of tolerance
      (is (every (lambda (p) (< (second p) 0.336d0)) points)
          "every solution in the table's front half (map y < 0.31, and half a cell): ~s"
          (remove-if (lambda (p) (< (second p) 0.336d0)) points))
      (is (every (lambda (p) (< (dist-xy p '(-3.38 0.31)) 0.24d0)) points)
          "every solution within 0.2 m (and a cell) of the table's centre")
      (is (null (cram-plans-compat::modern-location-description d))
          "(side front) does not make the designator one of the era's"))
    (let ((era (desig:make-designator :location '((:to :reach) (:side :left) (:obj nil)))))
      (is (equal '(:arm :left)
                 (assoc :arm (cram-plans-compat::modern-location-description era)))
          "beside (to reach), (side left) is still the era's arm"))))

(test table-setting-bowl-slot
  (with-household-kitchen ()
    (spawn :bowl-1 :bowl '((1.0 0.0 2.0) (0 0 0 1)))
    (let ((points (sample-points (man-int:get-object-destination :bowl :iai-kitchen nil :table-setting) 60)))
      (is (every (lambda (p) (and (<= -3.78 (first p) -2.98) (<= -0.33 (second p) 0.95))) points)
          "on the dining table")
      (is (every (lambda (p) (< (second p) 0.31d0)) points) "in its front half")
      (is (every (lambda (p) (< (abs (- (third p) (+ 0.7463d0 0.0502d0))) 5d-3)) points)
          "at the table top + the bowl's origin height")
      ;; CRAM's two slots: rows named by the table's longer side in the map (y), laid out in
      ;; the table's frame (turned a quarter), 0.03 + 0.1 m in from its long edges: one in the
      ;; back half (y 0.58), one in the front half (-3.38 0.04); 0.08 m around them
      (is (every (lambda (p) (< (dist-xy p '(-3.38 0.04)) 0.081d0)) points)
          "within 0.08 m of the front slot's centre")
      (is (some (lambda (p) (> (dist-xy p '(-3.38 0.04)) 0.03d0)) points)
          "spread around the slot centre"))))

(defun bowl-on-table ()
  "The bowl in the table's front slot."
  (spawn :bowl-1 :bowl '((-3.38 0.04 0.7965) (0 0 0 1))))

(test spoon-right-of-and-near-the-bowl
  (with-household-kitchen ()
    (bowl-on-table)
    (spawn :spoon-1 :spoon '((1.0 0.0 2.0) (0 0 0 1)))
    (let* ((destination (man-int:get-object-destination :spoon :iai-kitchen nil :table-setting))
           (poses (samples destination 40))
           (points (mapcar #'xyz poses)))
      (is (every (lambda (p) (<= 0.14 (dist-xy p '(-3.38 0.04)) 0.27)) points)
          "near: between the two objects' padded sizes and that plus their mean size")
      ;; as in CRAM, a person at the table sits at its front (map -y) edge: right is map +x
      (is (every (lambda (p) (let ((dx (- (first p) -3.38)) (dy (- (second p) 0.04)))
                               (and (> dx 0) (> (/ dx (sqrt (+ (* dx dx) (* dy dy)))) 0.9))))
                 points)
          "right of the bowl, within acos 0.9 of the direction")
      (is (every (lambda (p) (< (abs (- (third p) (+ 0.7463 0.0063))) 5d-3)) points) "on the table top")
      (let ((table (yaw-of (btr:link-pose (kitchen) "dining_area_jokkmokk_table_main"))))
        (is (every (lambda (pose) (< (abs (sin (* 2 (- (yaw-of pose) table)))) 1d-6)) poses)
            "aligned with the table's axes")))))

(test cup-right-of-and-behind-the-bowl
  (with-household-kitchen ()
    (bowl-on-table)
    (spawn :cup-1 :cup '((1.0 0.0 2.0) (0 0 0 1)))
    (let ((points (sample-points (man-int:get-object-destination :cup :iai-kitchen nil :table-setting) 40)))
      (is (every (lambda (p) (and (> (first p) -3.38) (> (second p) 0.04))) points)
          "right of (map +x) and behind (map +y, towards the table's middle) the bowl")
      (is (every (lambda (p) (<= 0.2 (dist-xy p '(-3.38 0.04)) 0.45)) points) "near the bowl"))))

(test far-from-keeps-away
  (with-household-kitchen ()
    (bowl-on-table)
    (let* ((table (desig:make-designator :object '((:type :counter-top) (:urdf-name :dining-area-jokkmokk-table-main)
                                                   (:part-of :iai-kitchen))))
           (points (sample-points (location `(:on ,table) `(:far-from ,(desig:an object (type bowl) (name bowl-1)))))))
      (is (every (lambda (p) (> (dist-xy p '(-3.38 0.04)) 0.3)) points) "beyond the far-from radius"))))

(test attachments-give-the-tray-slots
  (with-household-kitchen ()
    (let* ((destination (man-int:get-object-destination :bowl :iai-kitchen nil :table-cleaning))
           (first (desig:reference destination))
           (tray (btr:link-pose (kitchen) "sink_area_dish_washer_tray_bottom"))
           (expected (cl-transforms:transform-point (cl-transforms:pose->transform tray)
                                                    (cl-transforms:make-3d-vector 0.03 0.15 0.2))))
      (is (< (cl-transforms:v-dist (cl-transforms:origin first) expected) 1d-6)
          "the bowl's slot dish-washer-drawer-right, (0.03 0.15 0.2) in the tray frame")
      (let ((cups (cut:force-ll (costmap::attachment-poses
                                 (man-int:get-object-destination :cup :iai-kitchen nil :table-cleaning)))))
        (is (= 2 (length cups)))
        (is (< (abs (cl-transforms:x (cl-transforms:orientation (first cups)))) 1.000001)
            "flipped around x")))))

(test above-with-z-offset
  (with-household-kitchen ()
    (spawn :milk-1 :milk '((1.0 0.0 2.0) (0 0 0 1)))
    (let ((points (sample-points (man-int:get-object-destination :milk :iai-kitchen nil :table-cleaning))))
      (multiple-value-bind (lo hi) (link-box "sink_area_trash_drawer_main")
        (is (every (lambda (p) (inside-xy-p p lo hi)) points) "above the trash drawer")
        (is (every (lambda (p) (< (abs (- (third p) (+ (third hi) -0.05 0.0877))) 5d-3)) points)
            "at its top - 0.05 + the milk's origin height")))))

(test reachable-for-a-drawer-handle
  (with-household-kitchen ()
    (let* ((?drawer (drawer :sink-area-left-upper-drawer-main))
           (handle (costmap::environment-part-target ?drawer))
           (d (desig:a location (reachable-for pr2) (arm left) (object ?drawer)))
           (points (sample-points d 30)))
      (is (< (cl-transforms:v-dist handle (cl-transforms:make-3d-vector 1.203 0.900 0.773)) 0.02)
          "the target is the handle")
      (is (every (lambda (p) (< (first p) 1.203)) points) "in front of the furniture")
      (is (every (lambda (p) (< (second p) 0.900)) points)
          "for the left arm, the base stands right of the drawer's axis (map -y)")
      (let ((solution (desig:reference d)))
        (is (< (dist-xy (xyz solution) '(1.0 0.9)) 1.3) "a solution near the drawer")))))

(test restricted-area-applies-when-set
  (with-household-kitchen ()
    (spawn :bowl-1 :bowl '((-0.9 1.0 0.90) (0 0 0 1)))
    (let ((costmap:*restricted-area-function* #'costmap:kitchen-restricted-area))
      (let ((points (sample-points (desig:a location (visible-for pr2)
                                            (object (desig:an object (type bowl) (name bowl-1))))
                                   40)))
        (is (every (lambda (p) (= 1 (costmap:kitchen-restricted-area (first p) (second p)))) points)
            "every base pose in the allowed area")))
    (is (= 0 (costmap:kitchen-restricted-area 1.3 0)))
    (is (= 1 (costmap:kitchen-restricted-area -3 0.5)))
    (is (= 0 (costmap:kitchen-restricted-area -3 1.5)))))

(test household-location-bad-input
  (with-household-kitchen ()
    (flet ((message (designator)
             (handler-case (progn (costmap:designator-costmap designator) "no error")
               (error (e) (princ-to-string e)))))
      (let ((d (drawer :sink-area-left-upper-drawer-main)))
        (is (search "SIDEWAYS" (message (location `(:in ,d) '(:side :sideways)))))
        (is (search "NO-SUCH-DRAWER" (message (location `(:in ,(drawer :no-such-drawer))))))
        (is (search "\"fast\"" (message (location `(:in ,d) '(:range "fast")))))
        (is (search "NEAREST" (message (location `(:in ,(drawer :oven-area-area-right-drawer-main
                                                                 '(:level :nearest)))))))
        (is (search "UNKNOWN-SLOT"
                    (handler-case (progn (costmap::attachment-poses
                                          (location `(:above ,d) '(:attachments (:unknown-slot))))
                                         "no error")
                      (error (e) (princ-to-string e)))))))))

(test reachable-for-the-fridge-door
  (with-household-kitchen ()
    (let* ((?door (desig:make-designator :object '((:type :fridge) (:urdf-name :iai-fridge-door)
                                                   (:part-of :iai-kitchen))))
           (handle (costmap::environment-part-target ?door))
           (points (sample-points (desig:a location (reachable-for pr2) (arm right) (object ?door)) 30)))
      (is (string= "iai_fridge_door_joint" (cl-urdf:name (costmap::container-joint (kitchen) "iai_fridge_door"))))
      (is (< (cl-transforms:v-dist handle (cl-transforms:make-3d-vector 1.195 -0.730 0.990)) 0.02)
          "the target is the door's handle")
      (multiple-value-bind (closed open)
          (costmap::handle-positions-at-limits (kitchen) (costmap::container-joint (kitchen) "iai_fridge_door")
                                               handle)
        (is (< (cl-transforms:v-dist open (cl-transforms:make-3d-vector 0.695 -1.371 0.990)) 0.03)
            "the handle of the open door (pi/2)")
        (is (every (lambda (p) (and (>= (dist-xy p (xyz closed)) 0.3) (>= (dist-xy p (xyz open)) 0.3)))
                   points)
            "clear of the handle at both limits")))))

(test drawer-joint-and-handle-lookup
  (with-household-kitchen ()
    (let ((k (kitchen)))
      (is (string= "sink_area_left_upper_drawer_main_joint"
                   (cl-urdf:name (costmap::container-joint k "sink_area_left_upper_drawer_main"))))
      (is (string= "sink_area_dish_washer_door_joint"
                   (cl-urdf:name (costmap::container-joint k "sink_area_dish_washer_main")))
          "the dishwasher opens by its door")
      (is (string= "sink_area_dish_washer_tray_handle_left_side"
                   (costmap::handle-link k "sink_area_dish_washer_tray_bottom"))
          "the tray's handle bar, below its frame"))))

(test restricted-area-not-for-objects-on-the-robot
  (with-household-kitchen ()
    (let* ((bowl (spawn :bowl-1 :bowl '((0.3 0.0 1.0) (0 0 0 1))))
           (robot (btr:get-robot-object btr:*current-bullet-world*))
           (d (desig:a location (reachable-for pr2) (object (desig:an object (type bowl) (name bowl-1))))))
      (let ((costmap:*restricted-area-function* #'costmap:kitchen-restricted-area))
        (is-true (costmap::restricted-area-applies-p d))
        (btr:attach-object robot bowl :link "r_gripper_tool_frame")
        (is-false (costmap::restricted-area-applies-p d) "not while the robot holds the bowl"))
      (is-false (costmap::restricted-area-applies-p d) "not unless it is set"))))

(test table-setting-counter-on-the-island
  (with-household-kitchen ()
    (spawn :bowl-1 :bowl '((1.0 0.0 2.0) (0 0 0 1)))
    (let ((points (sample-points (man-int:get-object-destination :bowl :iai-kitchen nil :table-setting-counter))))
      (multiple-value-bind (lo hi) (link-box "kitchen_island_surface")
        (is (every (lambda (p) (inside-xy-p p lo hi)) points) "on the kitchen island")
        (is (every (lambda (p) (< (abs (- (third p) (+ (third hi) 0.0502))) 5d-3)) points))))
    (let ((points (sample-points (man-int:get-object-likely-location :cup :iai-kitchen nil :table-setting-counter))))
      (is (every (lambda (p) (< (dist-xy p (xyz (btr:link-pose (kitchen) "sink_area_surface"))) 0.5001)) points)
          "on the sink counter, within 0.5 m of its origin"))))

(test household-location-bad-values
  (with-household-kitchen ()
    (flet ((message (designator)
             (handler-case (progn (costmap:designator-costmap designator) "no error")
               (error (e) (princ-to-string e)))))
      (let ((table (desig:make-designator :object '((:type :counter-top) (:urdf-name :dining-area-jokkmokk-table-main)
                                                    (:part-of :iai-kitchen))))
            (d (drawer :sink-area-trash-drawer-main)))
        (is (search "-3" (message (location `(:on ,table) '(:context :table-setting) '(:object-count -3)))))
        (is (search "DINNER" (message (location `(:on ,table) '(:context :dinner)))))
        (is (search "UPSIDE-DOWN" (message (location `(:on ,table) '(:orientation :upside-down)))))
        (is (search "\"low\"" (message (location `(:above ,d) '(:z-offset "low")))))
        (is (search "BOWL-9" (message (location `(:on ,table)
                                                `(:left-of ,(desig:an object (type bowl) (name bowl-9)))))))
        (is (search "1.5" (message (location `(:on ,table) `(:near ,(desig:an object (type bowl) (name bowl-9)))
                                             '(:threshold 1.5)))))
        (is (search "\"sink\"" (message (location '(:in "sink")))))
        (is (search "(FRONT . RIGHT)" (message (location `(:on ,table) '(:side (:front . :right))))))))))

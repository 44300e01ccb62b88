;;;; Packages of the Bullet belief state: CL-URDF (URDF models), BTR (worlds, objects, Prolog
;;;; predicates, pictures, visibility) and BTR-UTILS (convenience functions of the tutorials).

(defpackage :cl-urdf
  (:use :cl)
  (:export #:parse-urdf #:urdf-error #:robot #:name #:links #:joints #:root-link #:source
           #:link #:joint #:parent #:child #:joint-type #:origin #:axis #:limits
           #:lower #:upper #:mimic #:collision #:visual
           #:child-joints #:parent-joint #:robot-link-names #:robot-joint-names
           #:rerooted-source #:text-origin #:robot-with-joint-origins #:moved-joints
           #:child-joints-in-order #:movable-joint-p #:first-descendant-link #:first-descendant-joint
           #:handle-link #:connecting-joint #:generate-urdf-string))

(defpackage :cram-bullet-reasoning
  (:nicknames :btr)
  (:use :cl :cram-prolog :cram-utilities)
  (:local-nicknames (:native :cram-native))
  (:export
   ;; worlds
   #:bt-world #:bt-reasoning-world #:*current-bullet-world* #:world-handle #:world
   #:copy-world #:with-copied-world #:with-stored-world #:with-world #:simulate #:step
   #:objects #:object #:%object #:add-object #:remove-object #:object-names #:world-state
   #:restore-world-state #:get-world-objects-pose-info #:restore-world-poses
   #:bullet-world #:destroy-world
   ;; objects
   #:item #:robot-object #:rigid-body #:rigid-bodies #:name #:pose #:object-pose
   #:item-type #:item-types #:object-type #:aabb #:link-aabbs #:link-count #:local-aabb #:bounding-box #:object-color #:link-colors
   #:collision-group-bits #:call-without-collisions #:*mesh-files* #:*all-meshes-as-compound* #:add-objects-to-mesh-list
   #:register-ros-package #:ros-package-directory #:define-object-kind #:object-kind-keys #:btr-error
   ;; the costmap visualization
   #:add-costmap-function-object #:add-costmap-sample-object #:add-vis-axis-object
   #:costmap-vis-object #:clear-costmap-vis-object
   ;; robots and environments
   #:urdf #:link-names #:joint-names #:link-pose #:joint-state #:joint-states #:robot-joint-values
   #:set-robot-state-from-joints #:joint-limits #:joint-lower-limit #:joint-upper-limit
   #:get-robot-object #:get-robot-name #:get-environment-object #:*environment-name*
   #:robot-object-p #:link-exists-p #:object-handle #:world-lock #:object-kind #:object-spec #:link-index #:joint-index
   #:attach-object #:detach-object #:detach-all-objects #:attached-objects #:object-attached
   #:available-arms
   ;; physics and geometry queries
   #:contact #:find-objects-in-contact #:find-all-contacts #:objects-in-contact-p
   #:robot-colliding-objects-without-attached #:object-not-in-collision
   #:stable #:stable-p #:supported-by #:above #:below #:above-p #:below-p
   ;; pictures and visibility
   #:debug-window #:*snapshot-directory* #:*debug-snapshots* #:png-snapshot #:snapshot
   #:*camera-pose* #:render-camera-image
   #:visible #:occluding-objects #:object-visible-p #:visibility-fraction
   #:*visibility-threshold* #:camera-pose
   ;; Prolog interface names
   #:retract #:assert #:attached #:object-pose-on #:link
   #:object-bottom-pose #:item #:robot-object #:with-stored-world
   ;; more of CRAM's API
   #:with-current-bullet-world #:prolog-?w #:?w #:clear-bullet-world #:obj-pose-on
   #:robot-attached-objects-in-collision #:calculate-bb-dims #:merge-bounding-boxes
   #:event #:make-event #:event-world-state #:timestamp #:timeline #:timeline-init
   #:timeline-advance #:timeline-events #:timeline-current-world-state #:timeline-lookup
   #:*current-timeline* #:with-timeline #:occurs-in #:holds-at))

(defpackage :cram-bullet-reasoning-utilities
  (:nicknames :btr-utils)
  (:use :cl)
  (:export #:spawn-object #:move-object #:kill-object #:kill-all-objects #:move-robot
           #:object-instance #:object-pose))

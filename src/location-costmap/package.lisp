;;;; Package CRAM-LOCATION-COSTMAP (nickname COSTMAP): location costmaps, and the metadata
;;;; predicates (map size, resolution, paddings, reach) that robot descriptions and
;;;; environments provide.

(defpackage :cram-location-costmap
  (:nicknames :costmap :location-costmap)
  (:use :cl :cram-prolog)
  (:export
   ;; metadata predicates
   #:costmap-size #:costmap-origin #:costmap-resolution
   #:costmap-padding #:costmap-manipulation-padding
   #:costmap-in-reach-distance #:costmap-reach-minimal-distance
   #:visibility-costmap-size #:orientation-samples #:orientation-sample-step
   #:robot-costmap-metadata #:current-robot-costmap-metadata #:user-costmap-metadata
   ;; costmaps
   #:location-costmap #:make-location-costmap #:get-cost-map #:get-map-value #:positive-cells-within
   #:no-cost-functions-registered #:gen-costmap-sample-point #:cost-functions
   #:height-generators #:orientation-generators
   #:costmap-samples #:register-cost-function #:register-height-generator
   #:register-orientation-generator #:register-orientation-ordering
   #:make-preferred-yaw-ordering #:costmap-generator-name->score
   #:desig-costmap #:merge-costmaps
   ;; cost functions and generators
   #:make-gauss-cost-function #:make-range-cost-function
   #:make-occupancy-grid-cost-function #:make-padding-mask
   #:make-constant-height-function #:make-matrix-cost-function
   #:make-axis-boundary-cost-function #:make-angle-to-point-generator
   #:make-orientation-generator #:make-identity-orientation-generator
   #:make-quarter-turns-orientation-generator
   ;; occupancy grids
   #:occupancy-grid #:make-occupancy-grid
   #:invalid-probability-distribution
   ;; costmap geometry, sampling and determinism
   #:origin-x #:origin-y #:resolution #:width #:height #:costmap-rows #:costmap-columns
   #:cost-function #:make-cost-function #:cost-function-name #:cost-function-bounds
   #:make-rectangle-cost-function #:make-line-of-sight-cost-function
   #:generate-orientations #:generate-heights #:costmap-metadata-value
   #:*costmap-random-state* #:seed-costmaps
   #:occupied-p #:occupancy-bits #:pad-occupancy-grid #:environment-occupancy-grid
   #:*occupancy-z-min* #:*occupancy-z-max*
   ;; designators and the belief state
   #:costmap #:costmap-add-function #:costmap-add-orientation-generator
   #:costmap-add-height-generator #:merged-desig-costmap #:designator-costmap
   #:costmap-location-generator #:visible-for-costmap #:reachable-for-costmap #:reachable-from-costmap #:on-costmap
   #:forget-designator-costmap
   #:robot-pose-collisions #:robot-pose-distance-validator
   #:robot-pose-visibility-validator #:robot-pose-collision-validator
   #:line-of-sight-p #:robot-camera-height
   ;; household locations
   #:kitchen-restricted-area #:*restricted-area-function* #:*attachments* #:*in-height-above-bottom*
   #:*table-setting-paddings* #:*slot-sizes* #:*slot-deviation* #:*relation-keys*
   #:container-level-link #:level-links
   ;; pictures
   #:costmap-heat-map-png #:costmap-heat-map-image))

;;;; Tests of the kitchen and shop layouts against the tutorials: the PR2 stands clear at the
;;;; 2017 tutorial's meal-table poses, and the shop's shelf levels are where the model facts put
;;;; them, with the milk of the Pepper page on the levels those heights give.

(defpackage :cram-scene-layout-tests
  (:use :cl :fiveam))

(in-package :cram-scene-layout-tests)

(def-suite scene-layout :in cram-plans-tests:all
  :description "The kitchen and shop layouts where the tutorials use them.")
(in-suite scene-layout)

(defun yaw-pose (x y yaw)
  (cl-transforms:make-pose (cl-transforms:make-3d-vector x y 0) (cl-transforms:yaw yaw)))

(defun robot-contacts (robot)
  (remove-duplicates
   (loop for (nil robot-link other other-link) in (btr::contact-records btr:*current-bullet-world* robot)
         collect (list robot-link (btr:name other) other-link))
   :test #'equal))

(test pr2-stands-clear-at-the-meal-table-poses
  (btw-tut:init-projection)
  (let ((robot (btr:get-robot-object)))
    ;; *meal-table-right-base-pose* and *meal-table-left-base-pose* of the 2017 tutorial, and
    ;; the 2022 tutorial's pose at the counter
    (dolist (pose (list (yaw-pose -2.0547 -0.481 (/ pi -2)) (yaw-pose -1.12 -0.42 (/ pi -2))
                        (yaw-pose -1.8547 -0.381 (/ pi -2))))
      (setf (btr:pose robot) pose)
      (is (null (robot-contacts robot)) "the PR2 at ~a touches ~s"
          (cl-transforms:origin pose) (robot-contacts robot)))))

(defun level-top (link)
  "The world z of the top of the shop's LINK."
  (cl-transforms:z (nth-value 1 (btr:aabb (btr:object btr:*current-bullet-world* :kitchen)
                                          (btr:link-index (btr:object btr:*current-bullet-world*
                                                                      :kitchen)
                                                          link)))))

(test shop-levels-are-at-the-heights-of-the-facts
  (demo:init-projection)
  ;; the tops of the level boards in the model facts (dm_shelves, z from room_link)
  (loop for (link top) in '(("shelf_1_level_1_link" 0.6163) ("shelf_1_level_2_link" 0.9513)
                            ("shelf_1_level_3_link" 1.329) ("shelf_1_level_4_link" 1.642)
                            ("shelf_1_level_5_link" 1.975)
                            ;; (the facts' shelf_2_shelf_2_level_N_link is named shelf_2_level_N_link
                            ;; here, as the seeds' shelf 2 links)
                            ("shelf_2_level_3_link" 0.9706) ("shelf_2_level_4_link" 1.277))
        do (is (< (abs (- top (level-top link))) 0.002) "~a's top is at ~,4f, the facts say ~,4f"
               link (level-top link) top)))

(defun supporting-level (name)
  "The level board of the shop under the centre of the object NAME whose top is closest below
(or at most 3 cm inside) the object's bottom."
  (let* ((world btr:*current-bullet-world*)
         (shop (btr:object world :kitchen))
         (object (btr:object world name))
         (centre (cl-transforms:origin (btr:pose object)))
         (bottom (cl-transforms:z (btr:aabb object))))
    (loop with best = nil and best-gap = 1d9
          for link in (btr:link-names shop)
          do (multiple-value-bind (lo hi) (btr:aabb shop (btr:link-index shop link))
               (let ((gap (- bottom (cl-transforms:z hi))))
                 (when (and (search "level" link) (not (search "support" link))
                            (not (search "divider" link))
                            (<= (cl-transforms:x lo) (cl-transforms:x centre) (cl-transforms:x hi))
                            (<= (cl-transforms:y lo) (cl-transforms:y centre) (cl-transforms:y hi))
                            (> gap -0.03) (< gap best-gap))
                   (setf best link best-gap gap))))
          finally (return best))))

(test milk-of-the-pepper-page-stands-on-the-levels-its-height-gives
  (demo:init-projection)
  ;; the page's spawn poses: MY-MILK1 at z 1.4 in shelf 1, MY-MILK2 at z 1.37 in shelf 2
  (btr:add-object btr:*current-bullet-world* :mesh 'my-milk1 '((4.1 -0.55 1.4) (0 0 1 1))
                  :mass 0 :mesh :milk)
  (btr:add-object btr:*current-bullet-world* :mesh 'my-milk2 '((1.5 -1.4 1.37) (0 0 1 1))
                  :mass 0 :mesh :milk)
  ;; the page's knowledge base says level 4 for both; at the heights of the facts the first
  ;; stands on shelf 1's level 3 (level 4's top is 0.24 m above its bottom)
  (is (equal "shelf_1_level_3_link" (supporting-level 'my-milk1)))
  (is (equal "shelf_2_level_4_link" (supporting-level 'my-milk2))))

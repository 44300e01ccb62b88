;;;; Tests of CRAM's household demo in projection (DEMOS): the spawn in closed containers, the
;;;; table set object by object, the kitchen cleaned up and closed again.

(defpackage :cram-plans-tests-household-demo
  (:use :cl :fiveam))

(in-package :cram-plans-tests-household-demo)

(def-suite household-demo :in cram-plans-tests:all
  :description "The household demo: set the breakfast table, then clean it up.")
(in-suite household-demo)

(defun object-position (type)
  (let ((o (btr:object btr:*current-bullet-world* (demos:demo-object-name type))))
    (and o (cl-transforms:origin (btr:pose o)))))

(defun near-p (position xyz tolerance)
  (< (cl-transforms:v-dist position (apply #'cl-transforms:make-3d-vector xyz)) tolerance))

(defun kitchen-joint (name)
  (btr:joint-state (btr:get-environment-object) name))

(defun run-quietly (thunk)
  "Call THUNK with the plan log captured; (values result-or-condition log)."
  (let* ((log (make-string-output-stream))
         (result (let ((cpl:*log-stream* log))
                   (handler-case (funcall thunk) (serious-condition (c) c)))))
    (values result (get-output-stream-string log))))

(test spawning-puts-each-object-into-its-closed-container
  (btw-tut:init-projection)
  (demos:initialize)
  (demos:spawn-objects-on-fixed-spots)
  ;; the map positions of the objects in the closed kitchen
  (is (near-p (object-position :bowl) '(1.455 0.950 0.468) 0.01))
  (is (near-p (object-position :cup) '(-0.953 1.029 0.509) 0.01))
  (is (near-p (object-position :spoon) '(1.430 0.900 0.741) 0.01))
  (is (near-p (object-position :breakfast-cereal) '(1.415 1.510 1.315) 0.01))
  (is (near-p (object-position :milk) '(1.370 -0.980 0.722) 0.01))
  ;; attached to their links: opening the bowl's drawer carries the bowl 0.48 m out
  (btr:set-robot-state-from-joints '(("sink_area_left_middle_drawer_main_joint" 0.48d0))
                                   (btr:get-environment-object))
  (is (near-p (object-position :bowl) '(0.975 0.950 0.468) 0.01))
  ;; initialize removes them and closes the drawer again
  (demos:initialize)
  (is (null (object-position :bowl)))
  (is (< (abs (kitchen-joint "sink_area_left_middle_drawer_main_joint")) 1d-6)))

(test unknown-object-types-are-named
  (btw-tut:init-projection)
  (let ((e (handler-case (demos:household-demo :object-list '(:bowl :unicorn))
             (error (e) e))))
    (is (typep e 'error))
    (is (search "UNICORN" (princ-to-string e)))))

(test transporting-a-missing-object-ends-in-searching-failed
  (btw-tut:init-projection)
  (demos:initialize)
  (demos:spawn-objects-on-fixed-spots :object-types '(:milk))
  (let ((result (run-quietly
                 (lambda ()
                   (urdf-proj:with-simulated-robot
                     (exe:perform (desig:an action (type transporting)
                                            (object (desig:an object (type bowl)))
                                            (context table-setting))))))))
    (is (typep result 'common-fail:searching-failed) "got ~a" result)))

(test household-demo-sets-and-cleans-the-table
  (btw-tut:init-projection)
  (let ((setting nil))
    ;; the table state after setting, taken from the objects' belief-state poses
    (multiple-value-bind (result log)
        (run-quietly
         (lambda ()
           (let ((demos::*after-setting-hook*
                   (lambda ()
                     (setf setting (loop for type in demos:*demo-object-types*
                                         collect (cons type (object-position type)))))))
             (demos:household-demo))))
      (is (equal demos:*demo-object-types* result) "the demo failed: ~a~%~a" result
          (subseq log (max 0 (- (length log) 3000))))
      (when setting
        (loop for (type . p) in setting
              do (is (and p (< -3.80 (cl-transforms:x p) -2.96)
                          (< -0.35 (cl-transforms:y p) 0.97)
                          (< 0.74 (cl-transforms:z p) 1.0))
                     "~s is not on the table after setting: ~a" type p))))
    ;; after cleaning: nothing held, the containers closed
    (is (null (btr:attached-objects (btr:get-robot-object))))
    (dolist (joint demos:*household-joints*)
      (is (< (abs (kitchen-joint joint)) 0.1) "~a is still open: ~a" joint (kitchen-joint joint)))
    ;; bowl, cup and spoon in the dishwasher tray's region, cereal back on the oven board, milk
    ;; in the trash drawer
    (let ((tray (btr:link-pose (btr:get-environment-object) "sink_area_dish_washer_tray_bottom")))
      (dolist (type '(:bowl :cup :spoon))
        (is (< (cl-transforms:v-dist (object-position type) (cl-transforms:origin tray)) 0.45)
            "~s is not in the dishwasher: ~a" type (object-position type))))
    (is (near-p (object-position :breakfast-cereal) '(1.415 1.510 1.315) 0.25))
    (let ((trash (btr:link-pose (btr:get-environment-object) "sink_area_trash_drawer_main")))
      (is (< (cl-transforms:v-dist (object-position :milk) (cl-transforms:origin trash)) 0.35)
          "the milk is not in the trash drawer: ~a" (object-position :milk)))))

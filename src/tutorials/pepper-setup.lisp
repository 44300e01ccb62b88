;;;; Package CRAM-PEPPER-DEMO (DEMO): Pepper as a shopping assistant in the shop of two shelves.
;;;; Setup of the belief state: the floor, the shelves (:KITCHEN), Pepper, the product meshes.

(defpackage :cram-pepper-demo
  (:nicknames :demo)
  (:use :cl :cram-prolog :cram-executive)
  (:export #:setup-bullet-world #:init-projection #:spawn-products-one #:spawn-human
           #:park-arms #:reposition-robot #:reposition-human #:menu-one #:menu-two
           #:interaction #:get-shelf-pose #:generate-robot-pose #:move-to-location #:demo-one
           #:find-product #:generate-look-directions #:get-left-pose #:get-right-pose
           #:get-product-type #:look-at-product #:get-robot-new-pose
           #:calculate-robot-navigation-goal-towards-target #:calculate-pose-towards-target
           #:point-front-right #:move-human-to-location #:get-human-new-pose
           #:*robot-parameter* #:*kitchen-parameter* #:*kitchen-urdf*))

(in-package :cram-pepper-demo)

(defvar *kitchen-urdf* nil "The parsed shop URDF, read once.")
(defvar *pepper-urdf* nil "The parsed Pepper URDF, read once.")
(defparameter *robot-parameter* "robot_description" "The ROS parameter with Pepper's URDF.")
(defparameter *kitchen-parameter* "shelf_description" "The ROS parameter with the shop's URDF.")

(defun read-description (parameter relative-path)
  (cl-urdf:parse-urdf
   (or (btw-tut::ros-parameter-string parameter)
       (uiop:read-file-string
        (merge-pathnames relative-path
                         (asdf:system-source-directory "cram-pepper-demo"))))))

(defun setup-bullet-world ()
  "A fresh belief state with the floor, the shop's shelves (named :KITCHEN) and Pepper."
  (let* ((robot (or *pepper-urdf*
                    (setf *pepper-urdf* (read-description *robot-parameter*
                                                          "robots/pepper/pepper.urdf"))))
         (kitchen (or *kitchen-urdf*
                      (setf *kitchen-urdf* (read-description *kitchen-parameter*
                                                             "resources/dm_shelves.urdf"))))
         (robot-name (rob-int:set-robot-name (cl-urdf:name robot))))
    (setf rob-int:*robot-urdf* robot
          btr:*environment-name* :kitchen
          cram-tf:*robot-base-frame* (or (rob-int::first-solution-value
                                          '?f `(rob-int:robot-base-frame ,robot-name ?f))
                                         (error "SETUP-BULLET-WORLD: the robot ~s has no base ~
                                                 frame fact." robot-name)))
    (btw-tut::fresh-world)
    (let ((world btr:*current-bullet-world*))
      (btr:add-object world :static-plane :floor '((0 0 0) (0 0 0 1))
                      :normal '(0 0 1) :constant 0)
      (btr:add-object world :urdf :kitchen '((0 0 0) (0 0 0 1)) :urdf kitchen
                      :collision-group :static-filter
                      :collision-mask '(:default-filter :character-filter) :compound t)
      (btr:add-object world :urdf robot-name '((0 0 0) (0 0 0 1)) :urdf robot)
      (btr:debug-window world))
    btr:*current-bullet-world*))

(defun init-projection ()
  "Set up the shop world and make the product meshes known."
  (coe:clear-belief)
  (setup-bullet-world)
  (setf cram-tf:*tf-default-timeout* 2.0
        prolog:*break-on-lisp-errors* t)
  (btr:add-objects-to-mesh-list "cram_plans_resources" :directory "meshes")
  btr:*current-bullet-world*)

(let* ((package (find-package :roslisp-utilities))
       (register (and package (find-symbol "REGISTER-ROS-INIT-FUNCTION" package))))
  (when (and register (macro-function register))
    (eval `(,register init-projection))))

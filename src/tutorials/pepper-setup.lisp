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

(defun read-description (parameter fallback-file)
  "The parsed URDF from the ROS parameter PARAMETER while a node runs and it is set, else from
FALLBACK-FILE (relative to the repository root)."
  (cl-urdf:parse-urdf (roslisp-utilities:robot-description-string
                       :parameter parameter :fallback-file fallback-file)))

(defparameter *pepper-root-link* "base_footprint"
  "The link Pepper's URDF is re-rooted at for the belief state: the footprint on the floor
(the URDF's own root, base_link, is the torso 0.82 m up), so that a robot pose with z 0
stands Pepper on the floor with its camera at eye height.")

(defun root-at (urdf link-name)
  "Make LINK-NAME the root link of the parsed URDF (BTR:ADD-OBJECT re-roots such a model)."
  (setf (slot-value urdf 'cl-urdf:root-link)
        (or (gethash link-name (cl-urdf:links urdf))
            (error "SETUP-BULLET-WORLD: the robot URDF ~s has no link ~s to root it at."
                   (cl-urdf:name urdf) link-name)))
  urdf)

(defun setup-bullet-world ()
  "A fresh belief state with the floor, the shop's shelves (named :KITCHEN) and Pepper, its
URDF re-rooted at *PEPPER-ROOT-LINK* so that it stands on the floor."
  (let* ((robot (root-at (or *pepper-urdf*
                             (setf *pepper-urdf* (read-description *robot-parameter*
                                                                   "robots/pepper/pepper.urdf")))
                         *pepper-root-link*))
         (kitchen (or *kitchen-urdf*
                      (setf *kitchen-urdf* (read-description *kitchen-parameter*
                                                             "resources/dm_shelves.urdf"))))
         (robot-name (rob-int:set-robot-name (cl-urdf:name robot))))
    (setf rob-int:*robot-urdf* robot
          rob-int:*environment-urdf* kitchen
          btr:*environment-name* :kitchen
          ;; the frame of the robot's pose in the belief state (its root), which CRAM-TF
          ;; reports as the robot's pose; the ROBOT-BASE-FRAME fact (base_link) names the torso
          cram-tf:*robot-base-frame* *pepper-root-link*)
    (btw-tut::fresh-world)
    (let ((world btr:*current-bullet-world*))
      (btr:add-object world :static-plane :floor '((0 0 0) (0 0 0 1))
                      :normal '(0 0 1) :constant 0)
      (btr:add-object world :urdf :kitchen '((0 0 0) (0 0 0 1)) :urdf kitchen
                      :collision-group :static-filter
                      :collision-mask '(:default-filter :character-filter) :compound t)
      ;; :compound t: link meshes (a URDF from the robot parameter) as one hull per sub-mesh
      (let ((pepper (btr:add-object world :urdf robot-name '((0 0 0) (0 0 0 1)) :urdf robot
                                    :compound t)))
        ;; the kinematic model the projection plans with is the re-rooted one
        (setf rob-int:*robot-urdf* (btr:urdf pepper)))
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

(roslisp-utilities:register-ros-init-function init-projection)

;;;; Containers as object types of MAN-INT: CRAM's hierarchy (container ⊃ container-prismatic ⊃
;;;; drawer; container ⊃ container-revolute ⊃ fridge, oven, dishwasher, cupboard; container ⊃
;;;; shelf), how they are gripped, how far they open, and the Prolog test OBJECT-IS-A-CONTAINER.

(in-package :cram-urdf-environment-manipulation)

(man-int:define-object-type :container)
(man-int:define-object-type :container-prismatic :container)
(man-int:define-object-type :drawer :container-prismatic)
(man-int:define-object-type :container-revolute :container)
(man-int:define-object-type :fridge :container-revolute)
(man-int:define-object-type :oven :container-revolute)
(man-int:define-object-type :dishwasher :container-revolute)
(man-int:define-object-type :cupboard :container-revolute)
(man-int:define-object-type :shelf :container)

;;; Handles are gripped with the gripper opened to 6 cm and CRAM's effort of containers.
(man-int:define-object-type-gripping :container :effort 50 :opening 0.06)

(defun container-type-p (type)
  "True when TYPE (a keyword) is :CONTAINER or one of its subtypes."
  (and (keywordp type) (man-int:object-type-subtype-p :container type)))

(defgeneric man-int:get-container-opening-distance (environment-name container-name)
  (:documentation "How far (metres or radians, an absolute joint value) accessing opens the
container CONTAINER-NAME (a keyword such as :SINK-AREA-DISH-WASHER-MAIN) of the environment
ENVIRONMENT-NAME (e.g. :IAI-KITCHEN); NIL means the upper limit of its joint. Add methods with
EQL specializers for containers that open less than their limit.")
  (:method (environment-name container-name)
    (declare (ignore environment-name container-name))
    nil)
  (:method ((environment-name (eql :iai-kitchen)) (container-name (eql :sink-area-dish-washer-main)))
    ;; the dishwasher door opens to 0.9 rad, not its limit pi/2: the tray must slide out above it
    0.9d0))

(def-fact-group container-types (man-int:object-is-a-container)
  (<- (man-int:object-is-a-container ?object-type)
    (bound ?object-type)
    (lisp-pred container-type-p ?object-type))
  (<- (man-int:object-is-a-container ?object-type)
    (not (bound ?object-type))
    (member ?object-type (:container :container-prismatic :drawer :container-revolute
                          :fridge :oven :dishwasher :cupboard :shelf))))

(setf (documentation 'man-int:object-is-a-container 'function)
      "Prolog predicate (man-int:object-is-a-container ?object-type): ?object-type is :CONTAINER
or one of its subtypes (:DRAWER, :FRIDGE, :CONTAINER-REVOLUTE ...).")

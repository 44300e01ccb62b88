;;;; Containers of an articulated environment: from the URDF name a user writes
;;;; (sink-area-left-upper-drawer-main, part-of iai-kitchen) to the container link, its handle
;;;; link, the joint that moves it, its state and limits, and the distance semantics of opening
;;;; and closing.

(in-package :cram-urdf-environment-manipulation)

(defparameter *container-state-convergence-delta* 0.1d0
  "Metres or radians within which a container joint counts as at a state (CPOE:CONTAINER-STATE).")

(defstruct (container (:constructor %make-container))
  "A container of an environment object: ENVIRONMENT (the BTR object), NAME (the keyword the user
wrote), LINK (its URDF link), HANDLE (the handle link), JOINT (the joint that moves it),
JOINT-TYPE (:PRISMATIC or :REVOLUTE), LOWER and UPPER (its limits) and TYPE (the designator's
object type, or NIL)."
  environment name link handle joint joint-type lower upper type)

(loop for (name text) in
      '((container-environment "The environment object (BTR) a CONTAINER belongs to.")
        (container-name "The keyword a CONTAINER was named with, e.g. :IAI-FRIDGE-DOOR.")
        (container-link "The URDF link name of a CONTAINER.")
        (container-handle "The URDF link name of a CONTAINER's handle.")
        (container-joint "The name of the joint that moves a CONTAINER.")
        (container-joint-type "The type of a CONTAINER's joint: :PRISMATIC or :REVOLUTE."))
      do (setf (documentation name 'function) text))

(defun urdf-name->link-name (urdf-name)
  "The URDF link name of URDF-NAME: a symbol such as SINK-AREA-LEFT-UPPER-DRAWER-MAIN becomes
\"sink_area_left_upper_drawer_main\"; a string stays as it is."
  (etypecase urdf-name
    (string urdf-name)
    (symbol (substitute #\_ #\- (string-downcase (symbol-name urdf-name))))))

(defun link-name->urdf-name (link-name)
  "The keyword a designator names LINK-NAME with: \"iai_fridge_door\" → :IAI-FRIDGE-DOOR."
  (intern (substitute #\- #\_ (string-upcase link-name)) :keyword))

(defvar *container-links-cache* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "CL-URDF robot → the sorted names of its container links.")

(defun container-link-p (link)
  "True for a link moved by its own joint (a drawer, a door, a tray) or carrying a hinged door
(a fridge, an oven, a dishwasher), with a handle below it."
  (and (or (let ((parent (cl-urdf:parent-joint link)))
             (and parent (cl-urdf:movable-joint-p parent)))
           (some (lambda (j) (member (cl-urdf:joint-type j) '(:revolute :continuous)))
                 (cl-urdf:child-joints link)))
       (cl-urdf:handle-link link)
       (cl-urdf:connecting-joint link)
       t))

(defun container-links (environment)
  "The names of the container links of ENVIRONMENT (a BTR object or its name), sorted."
  (let ((urdf (btr:urdf (environment-object environment))))
    (or (gethash urdf *container-links-cache*)
        (setf (gethash urdf *container-links-cache*)
              (sort (loop for link being the hash-values of (cl-urdf:links urdf)
                          when (container-link-p link) collect (cl-urdf:name link))
                    #'string<)))))

;;; ---- finding containers ----------------------------------------------------------------------

(defun environment-object (part-of)
  "The articulated object PART-OF names (a symbol or string, e.g. IAI-KITCHEN), or a BTR object
already; an error naming PART-OF when there is none."
  (cond ((typep part-of 'btr:robot-object) part-of)
        ((null part-of)
         (env-error "The container has no PART-OF: name the environment it belongs to, e.g. ~
                     (part-of iai-kitchen)."))
        ((not (or (symbolp part-of) (stringp part-of)))
         (env-error "PART-OF is ~s: expected the name of an environment object such as IAI-KITCHEN."
                    part-of))
        (t (let ((object (btr:object btr:*current-bullet-world*
                                     (intern (string-upcase (string part-of)) :keyword))))
             (unless (typep object 'btr:robot-object)
               (env-error "PART-OF ~s: there is no articulated environment object of that name in the ~
                           belief state; its articulated objects are ~{~s~^, ~}."
                          part-of
                          (loop for o in (btr:objects) when (typep o 'btr:robot-object)
                                collect (btr:name o))))
             object))))

(defun find-container (urdf-name part-of &optional type)
  "The CONTAINER of the environment PART-OF (e.g. IAI-KITCHEN) whose link URDF-NAME names (e.g.
SINK-AREA-LEFT-UPPER-DRAWER-MAIN or \"sink_area_left_upper_drawer_main\"); TYPE is the
designator's object type. An error naming the value when the environment or the link is
unknown (listing the container links), or the link is no container."
  (let* ((environment (environment-object part-of))
         (urdf (btr:urdf environment)))
    (unless (and urdf-name (or (symbolp urdf-name) (stringp urdf-name)))
      (env-error "URDF-NAME is ~s: expected the name of a container link of ~s such as ~s."
                 urdf-name (btr:name environment)
                 (link-name->urdf-name (first (container-links environment)))))
    (let* ((link-name (urdf-name->link-name urdf-name))
           (link (gethash link-name (cl-urdf:links urdf))))
      (unless link
        (env-error "URDF-NAME ~s: ~s has no link ~s. Its container links are: ~{~(~a~)~^, ~}."
                   urdf-name (btr:name environment) link-name
                   (mapcar #'link-name->urdf-name (container-links environment))))
      (let ((handle (cl-urdf:handle-link link))
            (joint (cl-urdf:connecting-joint link)))
        (unless (container-link-p link)
          (env-error "URDF-NAME ~s: the link ~s of ~s is no container (~:[it has no handle below ~
                      it~;no joint of its own moves it~]). Its container links are: ~{~(~a~)~^, ~}."
                     urdf-name link-name (btr:name environment) handle
                     (mapcar #'link-name->urdf-name (container-links environment))))
        (when (and type (keywordp type) (not (container-type-p type)))
          (env-error "The object type ~s of ~s is no container type: expected :CONTAINER or a ~
                      subtype (:DRAWER, :FRIDGE, :CONTAINER-PRISMATIC, :CONTAINER-REVOLUTE ...)."
                     type urdf-name))
        (let ((joint-type (if (eq (cl-urdf:joint-type joint) :prismatic) :prismatic :revolute)))
          (%make-container :environment environment
                           :name (if (symbolp urdf-name)
                                     (intern (symbol-name urdf-name) :keyword)
                                     (link-name->urdf-name urdf-name))
                           :link link-name :handle (cl-urdf:name handle)
                           :joint (cl-urdf:name joint) :joint-type joint-type
                           :lower (d (or (cl-urdf:lower joint) (- pi)))
                           :upper (d (or (cl-urdf:upper joint) pi))
                           :type type))))))

(defun designator-property (designator key)
  (desig:desig-prop-value (desig:current-desig designator) key))

(defun container-designator-container (designator)
  "The CONTAINER an object designator such as (an object (type drawer) (urdf-name ...) (part-of
iai-kitchen)) describes; an error naming what is missing or wrong."
  (unless (typep designator 'desig:object-designator)
    (env-error "Expected a container object designator with URDF-NAME and PART-OF, got ~s."
               designator))
  (let ((urdf-name (designator-property designator :urdf-name))
        (part-of (designator-property designator :part-of)))
    (unless urdf-name
      (env-error "The container designator ~s has no URDF-NAME: name its link, e.g. ~
                  (urdf-name sink-area-left-upper-drawer-main)." designator))
    (unless part-of
      (env-error "The container designator ~s has no PART-OF: name its environment, e.g. ~
                  (part-of iai-kitchen)." designator))
    (find-container urdf-name part-of (designator-property designator :type))))

(defun container-environment-name (container)
  (btr:name (container-environment container)))

;;; ---- states and distances ---------------------------------------------------------------------

(defun container-joint-limits (container)
  "(values lower upper) of the joint of CONTAINER."
  (values (container-lower container) (container-upper container)))

(defun container-joint-state (container)
  "The current value of CONTAINER's joint; a revolute joint's value is read modulo 2 pi, in
(-pi, pi]."
  (let ((value (btr:joint-state (container-environment container) (container-joint container))))
    (if (eq (container-joint-type container) :revolute)
        (let ((v (mod value (* 2 pi)))) (if (> v pi) (- v (* 2 pi)) v))
        value)))

(defun container-default-target (container action)
  "The joint value ACTION (:OPEN or :CLOSE) moves CONTAINER to without a distance: opening goes
to MAN-INT:GET-CONTAINER-OPENING-DISTANCE, else the upper limit; closing to the lower limit."
  (ecase action
    (:open (let ((distance (man-int:get-container-opening-distance
                            (container-environment-name container) (container-name container))))
             (if distance (d distance) (container-upper container))))
    (:close (container-lower container))))

(defun clip-target (container target)
  "TARGET clipped into the joint limits of CONTAINER, with a warning when it was beyond them."
  (let ((lower (container-lower container)) (upper (container-upper container)))
    (if (<= lower target upper)
        target
        (let ((clipped (max lower (min upper target))))
          (warn "Distance ~s of ~(~a~) is beyond the limits [~,4f, ~,4f] of its joint ~s; ~
                 clipped to ~,4f." target (container-name container) lower upper
                 (container-joint container) clipped)
          clipped))))

(defun check-distance (distance)
  (unless (or (null distance)
              (and (realp distance) (not (and (floatp distance) (sb-ext:float-nan-p distance)))
                   (< (abs distance) 1d6)))
    (env-error "DISTANCE is ~s: expected a joint value in metres or radians (a real)." distance))
  distance)

(defun container-opening-amount (container action &optional distance)
  "How far ACTION (:OPEN or :CLOSE) moves CONTAINER's joint to reach the absolute joint value
DISTANCE (default: CONTAINER-DEFAULT-TARGET), clipped to the limits: target - state for
opening, state - target for closing, never below 0 (opening an open drawer moves nothing).
Returns (values amount target)."
  (check-distance distance)
  (let* ((target (clip-target container (if distance (d distance)
                                            (container-default-target container action))))
         (state (container-joint-state container))
         (amount (ecase action
                   (:open (- target state))
                   (:close (- state target)))))
    (values (max 0d0 amount) target)))

;;;; What location designators refer to: robots, target points and objects, surfaces.

(in-package :cram-location-costmap)

(defun designator-robot-name (value)
  "The robot-description name meant by VALUE (e.g. :PR2 from (visible-for pr2)), compared by
symbol name with the described robots; an error naming VALUE when no description matches."
  (unless (and (symbolp value) value)
    (error "Location designator: the robot is ~s, expected a robot name such as PR2." value))
  (let ((described (rob-int:described-robot-names)))
    (or (find value described)
        (find (symbol-name value) described :key #'symbol-name :test #'string-equal)
        (error "Location designator: ~s is not a described robot; the loaded descriptions ~
                declare ~:[none~;~:*~{~s~^, ~}~]." value described))))

(defmacro with-robot ((robot-name) &body body)
  "Run BODY with ROB-INT:*ROBOT-NAME* bound to ROBOT-NAME, so the metadata is that robot's."
  `(let ((rob-int:*robot-name* ,robot-name)) ,@body))

(defun map-frame-p (frame)
  (member (string-left-trim "/" frame) '("map") :test #'string=))

(defun pose-in-map (pose what)
  "POSE (a pose or pose-stamped) as a CL-TRANSFORMS:POSE in the map frame. WHAT names POSE in
the error when it is neither: a string, or a function of no arguments that makes one (so that
a description is printed only for the error)."
  (cond ((typep pose 'cl-transforms-stamped:pose-stamped)
         (if (map-frame-p (cl-transforms-stamped:frame-id pose))
             (cl-transforms-stamped:pose-stamped->pose pose)
             (cl-transforms-stamped:pose-stamped->pose (cram-tf:ensure-pose-in-frame pose "map"))))
        ((typep pose 'cl-transforms:pose) pose)
        (t (error "~a: expected a pose or pose-stamped, got ~s."
                  (if (functionp what) (funcall what) what) pose))))

(defun object-center (object)
  "The centre of OBJECT's bounding box."
  (multiple-value-bind (lo hi) (btr:aabb object)
    (cl-transforms:v* (cl-transforms:v+ lo hi) 0.5d0)))

(defun item-of-type-p (object type)
  "True when OBJECT is an item with TYPE among its types (compared by name)."
  (and (typep object 'btr:item)
       (member (string type) (btr:item-types object) :key #'string :test #'string-equal)))

(defun held-by-robot-p (object &optional (world btr:*current-bullet-world*))
  "True when the robot of WORLD holds OBJECT (a belief-state object or NIL)."
  (let ((robot (and object (ignore-errors (btr:get-robot-object world)))))
    (and robot (btr:object-attached robot object) t)))

(defun find-object-by-type (type &optional (world btr:*current-bullet-world*))
  (find-if (lambda (o) (item-of-type-p o type)) (btr:objects world)))

(defun object-designator-world-object (designator &optional (world btr:*current-bullet-world*))
  "The belief-state object an object DESIGNATOR means: that of its perceived data, else the one
named by its NAME property, else the first item of its TYPE; NIL when there is none."
  (let* ((effective (desig:newest-effective-designator designator))
         (data (and effective (desig:designator-data effective)))
         (identifier (and data (ignore-errors (desig:object-identifier data))))
         (name (desig:desig-prop-value designator :name))
         (type (desig:desig-prop-value designator :type)))
    (or (and identifier (find-world-object identifier world))
        (and name (find-world-object name world))
        (and (null name) type (find-object-by-type type world)))))

(defun for-object (designator &optional (world btr:*current-bullet-world*))
  "The belief-state object that the FOR property of the location DESIGNATOR stands for: the one
its object designator means (OBJECT-DESIGNATOR-WORLD-OBJECT); else, when that names an object
the belief state does not have (CRAM's cleaning destinations say (for (an object (type bowl)
(name some-name)))), an item of its TYPE, one the robot holds first: the place is for an object
of that kind. NIL without a FOR object designator or such an object."
  (let ((for (desig:desig-prop-value designator :for)))
    (when (typep for 'desig:object-designator)
      (or (object-designator-world-object for world)
          (let ((type (desig:desig-prop-value for :type)))
            (and type (desig:desig-prop-value for :name)
                 (or (find-if (lambda (o) (and (item-of-type-p o type) (held-by-robot-p o world)))
                              (btr:objects world))
                     (find-object-by-type type world))))))))

(defun object-designator-target (designator &optional (world btr:*current-bullet-world*))
  "(values point object) of an object DESIGNATOR: the perceived pose, or the belief-state
object, or the reference of its LOCATION property."
  (let* ((effective (desig:newest-effective-designator designator))
         (data (and effective (desig:designator-data effective)))
         (object (object-designator-world-object designator world))
         (location (desig:desig-prop-value designator :location)))
    (cond (object (values (object-center object) object))
          ((and data (ignore-errors (desig:object-pose data)))
           (values (cl-transforms:origin (pose-in-map (desig:object-pose data) "object pose")) nil))
          (location (location-designator-target location))
          ((desig:desig-prop-value designator :urdf-name) (environment-part-target designator))
          (t (error "The object designator ~a does not name an object of the belief state ~
                     (by NAME, TYPE or perceived data; objects: ~{~s~^ ~}) and has no LOCATION."
                    designator (btr:object-names world))))))

(defun location-designator-target (designator)
  "The point of the solution the location DESIGNATOR stands at now: that of its newest
version (DESIG:CURRENT-DESIG), so that a robot location relative to a target follows the
target to its next solution when a plan retries with one."
  (let ((solution (desig:reference (desig:current-desig designator))))
    (values (cl-transforms:origin
             (pose-in-map solution (lambda () (format nil "solution of ~a" designator))))
            nil)))

(defun target-of (value &optional (world btr:*current-bullet-world*))
  "(values point object) for VALUE: an object or location designator, a pose or pose-stamped,
or a 3D-VECTOR."
  (typecase value
    (desig:object-designator (object-designator-target value world))
    (desig:location-designator (location-designator-target value))
    ((or cl-transforms-stamped:pose-stamped cl-transforms:pose)
     (values (cl-transforms:origin (pose-in-map value "target pose")) nil))
    (cl-transforms:3d-vector (values value nil))
    (t (error "Location target ~s: expected an object or location designator, a pose or a point."
              value))))

(defun object-designator-placed-p (designator &optional (world btr:*current-bullet-world*))
  "True when the object DESIGNATOR says where its object is: a belief-state object, a perceived
pose or a LOCATION property."
  (let* ((effective (desig:newest-effective-designator designator))
         (data (and effective (desig:designator-data effective))))
    (or (object-designator-world-object designator world)
        (and data (ignore-errors (desig:object-pose data)))
        (desig:desig-prop-value designator :location))))

(defun designator-target (designator)
  "(values point object) that a VISIBLE-FOR or REACHABLE-FOR DESIGNATOR is about: its OBJECT,
LOCATION or TARGET property. An OBJECT that says nothing about where it is, such as (an object
(type :shelf)) next to a LOCATION, only qualifies what is looked at: the LOCATION (or TARGET)
is the place then."
  (let* ((object (desig:desig-prop-value designator :object))
         (place (or (desig:desig-prop-value designator :location)
                    (desig:desig-prop-value designator :target)))
         (value (if (and place (typep object 'desig:object-designator)
                         (not (object-designator-placed-p object)))
                    place
                    (or object place))))
    (unless value
      (error "The location designator ~a needs an OBJECT, LOCATION or TARGET property to say ~
              what the robot should see or reach." designator))
    (target-of value)))

;;; ---- robots in the belief state ---------------------------------------------------------------

(defun robot-world-object (robot-name &optional (world btr:*current-bullet-world*))
  "The articulated object of ROBOT-NAME in WORLD, or NIL."
  (let ((o (find-world-object robot-name world)))
    (and o (btr:robot-object-p o) o)))

(defun robot-camera-height (robot-name &optional (world btr:*current-bullet-world*))
  "The camera height of ROBOT-NAME: its camera frame's height in WORLD when the robot is there,
kept within the CAMERA-MINIMAL-HEIGHT and CAMERA-MAXIMAL-HEIGHT facts."
  (let* ((min (cut:var-value '?h (cut:lazy-car (prolog `(rob-int:camera-minimal-height ,robot-name ?h)))))
         (max (cut:var-value '?h (cut:lazy-car (prolog `(rob-int:camera-maximal-height ,robot-name ?h)))))
         (robot (robot-world-object robot-name world))
         (current (and robot (ignore-errors
                              (cl-transforms:z (cl-transforms:origin
                                                (btr:camera-pose (btr:name robot) world)))))))
    (setf min (and (realp min) min) max (and (realp max) max))
    (cond (current (let ((z current))
                     (when min (setf z (max z min)))
                     (when max (setf z (min z max)))
                     z))
          (min min)
          (max max)
          (t (error "Robot ~s: no camera height (rob-int:camera-minimal-height) and no camera ~
                     in the belief state." robot-name)))))

(defun arm-lateral-offset (robot-name arm &optional (world btr:*current-bullet-world*))
  "The sideways offset (metres, left positive) of the first link of ARM from the base of the
robot ROBOT-NAME, from the belief state; 0 when the robot is not there."
  (unless (prolog `(rob-int:arm ,robot-name ,arm))
    (error "Location designator: ~s is not an arm of ~s (rob-int:arm facts)." arm robot-name))
  (let* ((robot (robot-world-object robot-name world))
         (links (ignore-errors (rob-int:get-arm-links robot-name arm)))
         (link (find-if (lambda (l) (and robot (btr:link-exists-p robot l))) links)))
    (if link
        (let* ((base (btr:pose robot))
               (local (cl-transforms:transform-point
                       (cl-transforms:transform-inv (cl-transforms:pose->transform base))
                       (cl-transforms:origin (btr:link-pose robot link)))))
          (cl-transforms:y local))
        0d0)))

;;; ---- surfaces ------------------------------------------------------------------------------------

(defun urdf-link-name (value)
  "The URDF link name for VALUE: strings as they are, symbols lower-cased with - as _."
  (etypecase value
    (string value)
    (symbol (substitute #\_ #\- (string-downcase (symbol-name value))))))

(defun surface-of (designator &optional (world btr:*current-bullet-world*))
  "(values x-min y-min x-max y-max top object link) of the surface an object DESIGNATOR names:
the link URDF-NAME of the environment PART-OF (default: the environment; LINK is its name), or
a belief-state object by NAME (LINK NIL)."
  (unless (typep designator 'desig:object-designator)
    (error "ON: expected an object designator such as (an object (type counter-top) (urdf-name ~
            sink-area-surface) (part-of iai-kitchen)), got ~s." designator))
  (let ((urdf-name (desig:desig-prop-value designator :urdf-name))
        (part-of (desig:desig-prop-value designator :part-of)))
    (flet ((box (lo hi object &optional link)
             (values (cl-transforms:x lo) (cl-transforms:y lo) (cl-transforms:x hi)
                     (cl-transforms:y hi) (cl-transforms:z hi) object link)))
      (cond (urdf-name
             (let* ((env (if part-of
                             (or (find-world-object part-of world)
                                 (error "ON: there is no object ~s (PART-OF of ~a) in the belief ~
                                         state; objects: ~{~s~^ ~}." part-of designator
                                         (btr:object-names world)))
                             (or (btr:get-environment-object world)
                                 (error "ON: ~a has no PART-OF and the belief state has no ~
                                         environment." designator))))
                    (link (urdf-link-name urdf-name)))
               (unless (btr:robot-object-p env)
                 (error "ON: ~s is not an articulated object with links." (btr:name env)))
               (let ((index (position link (btr:link-names env) :test #'string=)))
                 (unless index
                   (error "ON: ~s (from URDF-NAME ~s) is not a link of ~s." link urdf-name
                          (btr:name env)))
                 (multiple-value-bind (lo hi) (btr:aabb env index)
                   (box lo hi env link)))))
            (t (let ((object (object-designator-world-object designator world)))
                 (unless object
                   (error "ON: ~a names no link (URDF-NAME) and no object of the belief state."
                          designator))
                 (multiple-value-bind (lo hi) (btr:aabb object)
                   (box lo hi object))))))))

;;;; The simulated robot as the belief state and the robot-description facts describe it:
;;;; the robot object, its arms, torso, neck and cameras, frames resolved to the map.

(in-package :cram-urdf-projection)

(defvar *be-strict-with-collisions* nil
  "When true, the lenient collision modes of MOVE-TCP (:ALLOW-HAND, :ALLOW-FINGERS,
:ALLOW-ARM, :ALLOW-ATTACHED) check collisions of the rest of the robot; when NIL they allow
everything, as on CRAM.")

(defun projection-error (format-control &rest arguments)
  "Signal a SIMPLE-ERROR about bad input to the simulated robot."
  (error 'simple-error :format-control format-control :format-arguments arguments))

(defun robot-object (&optional (world btr:*current-bullet-world*))
  "The robot of WORLD (named as the current robot description); an error when there is none."
  (or (btr:get-robot-object world)
      (projection-error "There is no robot in the belief state ~s for the current robot ~s: ~
                         add it with (btr:assert ?w (btr:object :urdf <name> <pose> :urdf ...)) ~
                         and choose it with ROB-INT:SET-ROBOT-NAME."
                        world (ignore-errors (rob-int:current-robot-name)))))

(defun robot-name ()
  "The name of the current robot description."
  (rob-int:current-robot-name))

(defun plain-facts-p (functor)
  "True when every clause of FUNCTOR is a plain fact (see ROB-INT::PLAIN-FACTS-P)."
  (rob-int::plain-facts-p functor))

(defun cached-fact-solutions (query)
  "Every solution of QUERY over plain facts, kept while the database is the same; second value
NIL for any other query (see ROB-INT::CACHED-FACT-SOLUTIONS)."
  (rob-int::cached-fact-solutions query))

(defun fact-value (variable query)
  "The value of VARIABLE in the first solution of the Prolog QUERY, or NIL; second value: found."
  (multiple-value-bind (solutions cached) (cached-fact-solutions query)
    (let ((solutions (if cached solutions (prolog:prolog query))))
      (if solutions
          (values (cut:var-value variable (cut:lazy-car solutions)) t)
          (values nil nil)))))

(defun fact-values (variable query)
  "The values of VARIABLE in every solution of QUERY, without duplicates, in order."
  (multiple-value-bind (solutions cached) (cached-fact-solutions query)
    (remove-duplicates (mapcar (lambda (b) (cut:var-value variable b))
                               (if cached solutions (cut:force-ll (prolog:prolog query))))
                       :test #'equal :from-end t)))

(defun check-arm (arm)
  "ARM when the current robot has it; an error naming it and the known arms otherwise."
  (let ((arms (fact-values '?arm `(rob-int:arm ,(robot-name) ?arm))))
    (unless (member arm arms)
      (projection-error "Arm ~s: expected one of ~s for the robot ~s." arm arms (robot-name)))
    arm))

(defun robot-arms ()
  "The arms of the current robot."
  (fact-values '?arm `(rob-int:arm ,(robot-name) ?arm)))

(defun arm-joint-names (arm)
  "The joint names of ARM of the current robot, base to wrist."
  (check-arm arm)
  (rob-int:get-arm-joints (robot-name) arm))

(defun end-effector-link (arm)
  "The end-effector link of ARM (grasped objects are attached to it)."
  (check-arm arm)
  (or (fact-value '?link `(rob-int:end-effector-link ,(robot-name) ,arm ?link))
      (projection-error "Robot ~s has no END-EFFECTOR-LINK fact for the arm ~s." (robot-name) arm)))

(defun tool-frame (arm)
  "The tool frame name of ARM (a link of the robot when it exists there)."
  (check-arm arm)
  (fact-value '?frame `(rob-int:robot-tool-frame ,(robot-name) ,arm ?frame)))

(defvar *tcp-in-ee-memo* nil
  "NIL, or a cons whose car is an alist of (arm robot transform . inverse) that
TCP-IN-EE-TRANSFORM fills and reads: bound by WITH-TCP-IN-EE-KEPT.")

(defmacro with-tcp-in-ee-kept (&body body)
  "Run BODY with each arm's TCP-IN-EE-TRANSFORM computed once: for a check whose motions the
robot's facts and special variables (a TCP-IN-EE-POSE rule may read one) do not change under.
Inside another, the outer one's answers are shared."
  `(let ((*tcp-in-ee-memo* (or *tcp-in-ee-memo* (list nil)))) ,@body))

(defun tcp-in-ee-transform (arm &optional (robot (robot-object)))
  "The tool frame in the end-effector link frame of ARM, as a CL-TRANSFORMS:TRANSFORM: the
TCP-IN-EE-POSE fact, else the current relative pose of the tool frame link, else identity.
Second value: its inverse."
  (let ((memo *tcp-in-ee-memo*))
    (if memo
        (let ((kept (loop for entry in (car memo)
                          when (and (eq (first entry) arm) (eq (second entry) robot))
                            return (cddr entry))))
          (if kept
              (values (car kept) (cdr kept))
              (multiple-value-bind (transform inverse steady) (%tcp-in-ee-transform arm robot t)
                ;; not one that follows a joint (a tool link below a gripper joint)
                (when steady (push (list* arm robot transform inverse) (car memo)))
                (values transform inverse))))
        (%tcp-in-ee-transform arm robot))))

(defun %tcp-in-ee-transform (arm robot &optional steadiness)
  "TCP-IN-EE-TRANSFORM, without the memo; with STEADINESS, a third value: true unless it
follows a joint."
  (let* ((pose (fact-value '?pose `(rob-int:tcp-in-ee-pose ,(robot-name) ?pose)))
         (tool (tool-frame arm))
         (ee (end-effector-link arm))
         (link (and (not pose) tool (btr:link-exists-p robot tool)))
         (transform
           (cond (pose (cl-transforms:pose->transform (btr::ensure-pose pose "TCP-IN-EE pose")))
                 (link (relative-transform (btr:link-pose robot ee) (btr:link-pose robot tool)))
                 (t (cl-transforms:make-identity-transform)))))
    ;; a tool link below a gripper joint moves with it
    (values transform (cl-transforms:transform-inv transform)
            (and steadiness (or (not link) (fixed-below-p robot ee tool))))))

(defun fixed-below-p (robot ancestor link)
  "True when the URDF link LINK of ROBOT hangs below its link ANCESTOR through fixed joints
only (so that it keeps its pose relative to ANCESTOR)."
  (let ((links (cl-urdf:links (btr:urdf robot))))
    (loop for l = (gethash link links) then (cl-urdf:parent joint)
          for joint = (and l (cl-urdf:parent-joint l))
          do (cond ((null l) (return nil))
                   ((string= (cl-urdf:name l) ancestor) (return t))
                   ((or (null joint) (not (eq (cl-urdf:joint-type joint) :fixed))) (return nil))))))

(defun relative-transform (parent-pose child-pose)
  "The transform of CHILD-POSE expressed in the frame of PARENT-POSE (both in one frame)."
  (cl-transforms:transform* (cl-transforms:transform-inv (cl-transforms:pose->transform parent-pose))
                            (cl-transforms:pose->transform child-pose)))

(defun torso-joint ()
  "The torso joint name of the current robot and its link, or NIL when it has none."
  (multiple-value-bind (bindings)
      (cut:lazy-car (rob-int::fact-solutions `(rob-int:robot-torso-link-joint ,(robot-name) ?link ?joint)))
    (values (and bindings (cut:var-value '?joint bindings))
            (and bindings (cut:var-value '?link bindings)))))

(defun movable-joint-p (robot joint)
  "True when JOINT is a movable (revolute, continuous, prismatic) joint of ROBOT."
  (let ((urdf-joint (and (stringp joint) (gethash joint (cl-urdf:joints (btr:urdf robot))))))
    (and urdf-joint (cl-urdf:movable-joint-p urdf-joint))))

(defun neck-joints ()
  "The neck joints of the current robot, base first."
  (let ((bindings (cut:lazy-car (rob-int::fact-solutions `(rob-int:robot-neck-joints ,(robot-name) . ?joints)))))
    (and bindings (cut:var-value '?joints bindings))))

(defun camera-frame (&optional (robot (robot-object)))
  "The first camera frame of the current robot that is a link of ROBOT."
  (or (find-if (lambda (f) (btr:link-exists-p robot f))
               (fact-values '?frame `(rob-int:camera-frame ,(robot-name) ?frame)))
      (projection-error "Robot ~s has no CAMERA-FRAME fact naming one of its links." (robot-name))))

(defun robot-base-frame ()
  "The base frame of the current robot (ROBOT-BASE-FRAME fact), default the root link."
  (or (fact-value '?frame `(rob-int:robot-base-frame ,(robot-name) ?frame))
      (cl-urdf:name (cl-urdf:root-link (btr:urdf (robot-object))))))

(defun link-descendants (robot link)
  "LINK and every link below it in ROBOT's URDF tree."
  (let* ((model (btr:urdf robot))
         (start (gethash link (cl-urdf:links model))))
    (unless start
      (projection-error "Link ~s is not a link of ~s." link (btr:name robot)))
    (labels ((walk (l)
               (cons (cl-urdf:name l)
                     (loop for j in (cl-urdf:child-joints l) append (walk (cl-urdf:child j))))))
      (walk start))))

(defun hand-links (arm &optional (robot (robot-object)))
  "The hand links of ARM: the HAND-LINKS fact, else every link below the end-effector link."
  (or (fact-value '?links `(rob-int:hand-links ,(robot-name) ,arm ?links))
      (link-descendants robot (end-effector-link arm))))

(defun gripper-joints (arm)
  "The gripper joints of ARM (GRIPPER-JOINT facts)."
  (check-arm arm)
  (or (fact-values '?joint `(rob-int:gripper-joint ,(robot-name) ,arm ?joint))
      (projection-error "Robot ~s has no GRIPPER-JOINT fact for the arm ~s." (robot-name) arm)))

(defun named-joint-states (type id name)
  "The named configuration NAME of the part TYPE/ID (e.g. :arm :left :park) as (joint value) pairs."
  (rob-int:get-robot-joint-states (robot-name) type id name))

(defun clamp-joint (robot joint value)
  "VALUE clamped to the limits of JOINT of ROBOT (continuous joints are left as they are)."
  (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
    (if (and lo hi (< lo hi)) (max lo (min hi value)) value)))

(defun current-robot-state (&optional (robot (robot-object)))
  "The base pose and the joint states of ROBOT, for comparisons after a motion."
  (list (btr:pose robot) (btr:joint-states robot)))

;;; ---- frames ---------------------------------------------------------------------------------

(defun frame-pose-in-map (frame &optional (world btr:*current-bullet-world*))
  "The map pose of FRAME: \"map\", a link of the robot, a link of another articulated object,
or a frame the current TF transformer knows."
  (let ((frame (string-left-trim "/" frame))
        (robot (btr:get-robot-object world)))
    (cond ((string= frame cram-tf:*fixed-frame*) (cl-transforms:make-identity-pose))
          ((and robot (btr:link-exists-p robot frame)) (btr:link-pose robot frame))
          ((loop for o in (btr:objects world)
                 when (and (typep o 'btr:robot-object) (btr:link-exists-p o frame))
                   return (btr:link-pose o frame)))
          (t (let ((ps (cl-transforms-stamped:transform-pose-stamped
                        cram-tf:*transformer*
                        :target-frame cram-tf:*fixed-frame*
                        :pose (cl-transforms-stamped:make-pose-stamped
                               frame 0d0 (cl-transforms:make-identity-vector)
                               (cl-transforms:make-identity-rotation))
                        :timeout 0)))
               (cl-transforms:make-pose (cl-transforms:origin ps) (cl-transforms:orientation ps)))))))

(defun pose-in-map (pose &optional (what "pose"))
  "POSE as a CL-TRANSFORMS:POSE in the map: a POSE-STAMPED in any known frame, a pose (taken
as in the map) or ((x y z) (qx qy qz qw))."
  (cond ((typep pose 'cl-transforms-stamped:pose-stamped)
         (let ((frame (cl-transforms-stamped:frame-id pose)))
           (cl-transforms:transform->pose
            (cl-transforms:transform* (cl-transforms:pose->transform (frame-pose-in-map frame))
                                      (cl-transforms:pose->transform pose)))))
        ((cl-transforms:pose-p pose) pose)
        ((consp pose) (btr::ensure-pose pose what))
        (t (projection-error "~a ~s: expected a pose-stamped, a pose or ((x y z) (qx qy qz qw))."
                             what pose))))

(defun pose-in-frame (map-pose frame)
  "The pose-stamped of MAP-POSE (in the map) expressed in FRAME."
  (let ((tr (cl-transforms:transform*
             (cl-transforms:transform-inv (cl-transforms:pose->transform (frame-pose-in-map frame)))
             (cl-transforms:pose->transform map-pose))))
    (cl-transforms-stamped:make-pose-stamped frame (cram-tf-stamp)
                                             (cl-transforms:translation tr)
                                             (cl-transforms:rotation tr))))

(defun cram-tf-stamp ()
  "The stamp for transforms and poses the projection makes: Unix time in seconds."
  (multiple-value-bind (s us) (sb-ext:get-time-of-day) (+ s (/ us 1d6))))

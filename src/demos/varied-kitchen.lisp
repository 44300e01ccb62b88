;;;; The varied kitchen of the household demo: the dining table and the kitchen island stand a
;;;; little elsewhere, drawn from a seeded random state, so a campaign tries the plans against
;;;; many layouts of the same furniture.

(in-package :cram-projection-demos)

(defparameter *varied-footprints*
  '(("dining_area_footprint_joint" 0.15 0.15 0.15)
    ("kitchen_island_footprint_joint" 0.05 0.05 0.0))
  "(joint dx dy dyaw): the fixed joints of the kitchen's furniture footprints that a varied
kitchen moves, and the largest offsets (metres, radians) of each.")

(defvar *varied-kitchen-random-state* (sb-ext:seed-random-state 4711)
  "The random state the varied kitchen layouts are drawn from (set it to repeat a layout).")

(defun parse-triple (text)
  (with-input-from-string (s text)
    (loop repeat 3 collect (let ((*read-default-float-format* 'double-float)) (read s)))))

(defun moved-origin (xyz rpy dx dy dyaw)
  "The <origin> element of a footprint joint at XYZ / RPY (text) moved by DX, DY and DYAW; its
xyz and rpy texts as second and third values."
  (destructuring-bind (x y z) (parse-triple xyz)
    (destructuring-bind (r p yaw) (parse-triple rpy)
      (let ((xyz (format nil "~f ~f ~f" (+ x dx) (+ y dy) z))
            (rpy (format nil "~f ~f ~f" r p (+ yaw dyaw))))
        (values (format nil "<origin xyz=\"~a\" rpy=\"~a\"/>" xyz rpy) xyz rpy)))))

(defun vary-urdf-text (text &optional (state *varied-kitchen-random-state*))
  "TEXT (a kitchen URDF) with the footprint joints of *VARIED-FOOTPRINTS* moved by offsets drawn
uniformly from STATE within their bounds. Second value: the new origins, an alist of joint
name -> origin as CL-URDF:PARSE-URDF reads them from the new text; third value: their texts, a
list of (joint-name xyz rpy)."
  (flet ((uniform (bound) (if (zerop bound) 0d0 (- (random (* 2d0 bound) state) bound))))
    (let ((origins '()) (texts '()))
      (dolist (entry *varied-footprints* (values text (nreverse origins) (nreverse texts)))
        (destructuring-bind (joint mx my myaw) entry
          (let* ((start (or (search (format nil "<joint name=\"~a\"" joint) text)
                            (demo-error "The kitchen URDF has no joint ~s to vary." joint)))
                 (origin (search "<origin" text :start2 start))
                 (end (+ 2 (search "/>" text :start2 origin)))
                 (element (subseq text origin end))
                 (xyz (subseq element (+ 5 (search "xyz=\"" element))
                              (position #\" element :start (+ 5 (search "xyz=\"" element)))))
                 (rpy (subseq element (+ 5 (search "rpy=\"" element))
                              (position #\" element :start (+ 5 (search "rpy=\"" element))))))
            (multiple-value-bind (moved new-xyz new-rpy)
                (moved-origin xyz rpy (uniform mx) (uniform my) (uniform myaw))
              (push (cons joint (cl-urdf:text-origin new-xyz new-rpy joint)) origins)
              (push (list joint new-xyz new-rpy) texts)
              (setf text (concatenate 'string (subseq text 0 origin) moved (subseq text end))))))))))

(defvar *kitchen-urdf* nil
  "NIL, or (text . robot): the kitchen URDF text VARY-KITCHEN last read and its parse, from which
each varied kitchen is copied with its moved footprints (CL-URDF:ROBOT-WITH-JOINT-ORIGINS).")

(defun kitchen-urdf (text)
  "The parse of the kitchen URDF TEXT (CL-URDF:PARSE-URDF), kept while the text is the same."
  (let ((known *kitchen-urdf*))
    (if (and known (string= (car known) text))
        (cdr known)
        (let ((robot (cl-urdf:parse-urdf text)))
          (setf *kitchen-urdf* (cons text robot))
          robot))))

(defun vary-kitchen ()
  "Replace the kitchen of the belief state by one whose furniture of *VARIED-FOOTPRINTS* stands
a little elsewhere (see VARY-URDF-TEXT). Objects attached to the old kitchen are dropped, so
call it before spawning."
  (let* ((world btr:*current-bullet-world*)
         (old (kitchen))
         (name (btr:name old))
         (original (roslisp-utilities:robot-description-string
                    :parameter btw-tut:*kitchen-parameter*
                    :fallback-file "resources/iai_kitchen.urdf")))
    (multiple-value-bind (text origins moved) (vary-urdf-text original)
      (btr:detach-all-objects old)
      (btr:remove-object world name)
      (btr:add-object world :urdf name '((0 0 0) (0 0 0 1))
                      :urdf (cl-urdf:robot-with-joint-origins (kitchen-urdf original) origins
                                                              :source text :moved moved)
                      :collision-group :static-filter
                      :collision-mask '(:default-filter :character-filter)))
    (btr:get-environment-object)))

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

(defvar *footprint-spans* nil
  "NIL, or (text . spans): FOOTPRINT-SPANS' answer for the kitchen text it was last asked of.")

(defun footprint-spans (text)
  "Where the <origin> elements of the joints of *VARIED-FOOTPRINTS* stand in TEXT, in their
order: a list of (start end xyz rpy), the element being TEXT from START below END and XYZ, RPY
its attribute texts. Kept for the same text object (a kitchen file is read once)."
  (let ((known *footprint-spans*))
    (if (and known (eq (car known) text))
        (cdr known)
        (let ((spans
                (loop for (joint) in *varied-footprints*
                      collect (let* ((start (or (search (format nil "<joint name=\"~a\"" joint) text)
                                                (demo-error "The kitchen URDF has no joint ~s to vary." joint)))
                                     (origin (search "<origin" text :start2 start))
                                     (end (+ 2 (search "/>" text :start2 origin)))
                                     (element (subseq text origin end)))
                                (flet ((attribute (name)
                                         (let ((at (+ (length name) 2 (search (format nil "~a=\"" name) element))))
                                           (subseq element at (position #\" element :start at)))))
                                  (list origin end (attribute "xyz") (attribute "rpy")))))))
          (setf *footprint-spans* (cons text spans))
          spans))))

(defun vary-urdf-text (text &optional (state *varied-kitchen-random-state*))
  "TEXT (a kitchen URDF) with the footprint joints of *VARIED-FOOTPRINTS* moved by offsets drawn
uniformly from STATE within their bounds. Second value: the new origins, an alist of joint
name -> origin as CL-URDF:PARSE-URDF reads them from the new text; third value: their texts, a
list of (joint-name xyz rpy)."
  (flet ((uniform (bound) (if (zerop bound) 0d0 (- (random (* 2d0 bound) state) bound))))
    (let ((origins '()) (texts '()) (replacements '()))
      (loop for (joint mx my myaw) in *varied-footprints*
            for (start end xyz rpy) in (footprint-spans text)
            do (multiple-value-bind (moved new-xyz new-rpy)
                   (moved-origin xyz rpy (uniform mx) (uniform my) (uniform myaw))
                 (push (cons joint (cl-urdf:text-origin new-xyz new-rpy joint)) origins)
                 (push (list joint new-xyz new-rpy) texts)
                 (push (list start end moved) replacements)))
      ;; the new text in one piece: the elements replaced in the order they stand in TEXT
      (let ((pieces '()) (at 0))
        (dolist (r (sort replacements #'< :key #'first))
          (destructuring-bind (start end moved) r
            (push (subseq text at start) pieces)
            (push moved pieces)
            (setf at end)))
        (push (subseq text at) pieces)
        (values (apply #'concatenate 'string (nreverse pieces))
                (nreverse origins) (nreverse texts))))))

(defvar *kitchen-urdf* nil
  "NIL, or (text . robot): the kitchen URDF text VARY-KITCHEN last read and its parse, from which
each varied kitchen is copied with its moved footprints (CL-URDF:ROBOT-WITH-JOINT-ORIGINS).")

(defun kitchen-urdf (text)
  "The parse of the kitchen URDF TEXT (CL-URDF:PARSE-URDF), kept while the text is the same."
  (let ((known *kitchen-urdf*))
    (if (and known (or (eq (car known) text) (string= (car known) text)))
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

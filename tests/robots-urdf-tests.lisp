;;;; Every link and joint the robot descriptions name must exist in the project's URDF
;;;; of that robot, named configurations must respect the URDF joint limits, and the PR2
;;;; tool offset must match the URDF kinematics.

(in-package :cram-robots-tests)

(in-suite robots)

(defstruct urdf-joint
  "The parts of a URDF joint the tests compare against."
  name type parent child xyz rpy lower upper)

(defstruct urdf-model
  "The link names and joints (by name) of a URDF file."
  name links joints)

(defun parse-numbers (text)
  "The numbers in the whitespace-separated TEXT, as double-floats."
  (with-standard-io-syntax
    (let ((*read-default-float-format* 'double-float)
          (*read-eval* nil))
      (mapcar (lambda (token)
                (let ((value (read-from-string token)))
                  (unless (realp value)
                    (error "Expected a number in the URDF, got ~s." token))
                  (coerce value 'double-float)))
              (remove "" (uiop:split-string text :separator '(#\Space #\Tab #\Newline))
                      :test #'string=)))))

(defun child-elements (element tag)
  "The direct child elements of ELEMENT named TAG."
  (loop for node across (dom:child-nodes element)
        when (and (dom:element-p node) (string= tag (dom:tag-name node)))
          collect node))

(defun attribute-or-nil (element name)
  (and element (dom:has-attribute element name) (dom:get-attribute element name)))

(defun read-urdf-model (pathname)
  "Parse the URDF file PATHNAME into a URDF-MODEL."
  (let* ((document (cxml:parse-file pathname (cxml-dom:make-dom-builder)))
         (root (dom:document-element document))
         (joints (make-hash-table :test 'equal)))
    (dolist (element (child-elements root "joint"))
      (let ((origin (first (child-elements element "origin")))
            (limit (first (child-elements element "limit")))
            (name (dom:get-attribute element "name")))
        (setf (gethash name joints)
              (make-urdf-joint
               :name name
               :type (dom:get-attribute element "type")
               :parent (attribute-or-nil (first (child-elements element "parent")) "link")
               :child (attribute-or-nil (first (child-elements element "child")) "link")
               :xyz (parse-numbers (or (attribute-or-nil origin "xyz") "0 0 0"))
               :rpy (parse-numbers (or (attribute-or-nil origin "rpy") "0 0 0"))
               :lower (let ((v (attribute-or-nil limit "lower"))) (and v (first (parse-numbers v))))
               :upper (let ((v (attribute-or-nil limit "upper"))) (and v (first (parse-numbers v))))))))
    (make-urdf-model
     :name (dom:get-attribute root "name")
     :links (mapcar (lambda (e) (dom:get-attribute e "name")) (child-elements root "link"))
     :joints joints)))

(defun robot-urdf-pathname (directory)
  "The project's URDF of the robot in robots/DIRECTORY/."
  (asdf:system-relative-pathname "cram-plans/cram-robot-interfaces"
                                 (format nil "robots/~a/~a.urdf" directory directory)))

(defmacro with-urdf ((model directory) &body body)
  "Run BODY with MODEL bound to the parsed URDF of robots/DIRECTORY/, or skip the test
with a message when the file does not exist."
  (let ((path (gensym "PATH")))
    `(let ((,path (robot-urdf-pathname ,directory)))
       (if (probe-file ,path)
           (let ((,model (read-urdf-model ,path)))
             ,@body)
           (skip "No URDF at ~a: the link and joint names cannot be checked." ,path)))))

(defun solutions-of (variables query)
  "The values of VARIABLES in every solution of QUERY, flattened into one list of strings."
  (loop for bindings in (cut:force-ll (prolog:prolog query))
        append (loop for variable in variables
                     for value = (cut:var-value variable bindings)
                     append (if (listp value) (copy-list value) (list value)))))

(defun named-links (robot)
  "Every link or frame name the descriptions state for ROBOT (the odometry frame lies
outside the robot model and is left out)."
  (remove-duplicates
   (remove-if-not
    #'stringp
    (append (solutions-of '(?x) `(rob-int:robot-base-frame ,robot ?x))
            (solutions-of '(?x) `(rob-int:robot-base-link ,robot ?x))
            (solutions-of '(?x) `(rob-int:robot-torso-link-joint ,robot ?x ?_))
            (solutions-of '(?x) `(rob-int:arm-links ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:end-effector-link ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:robot-tool-frame ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:hand-links ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:robot-neck-links ,robot . ?x))
            (solutions-of '(?x) `(rob-int:robot-neck-base-link ,robot ?x))
            (solutions-of '(?x) `(rob-int:camera-frame ,robot ?x))))
   :test #'string=))

(defun named-joints (robot)
  "Every joint name the descriptions state for ROBOT, including those of named
configurations."
  (remove-duplicates
   (remove-if-not
    #'stringp
    (append (solutions-of '(?x) `(rob-int:robot-torso-link-joint ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:arm-joints ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:gripper-joint ,robot ?_ ?x))
            (solutions-of '(?x) `(rob-int:robot-neck-joints ,robot . ?x))
            (mapcar #'first (solutions-of '(?x) `(rob-int:robot-joint-states ,robot ?_ ?_ ?_ ?x)))))
   :test #'string=))

(defun missing-names (names present)
  (sort (set-difference names present :test #'string=) #'string<))

(defun joint-state-entries (robot)
  "Every (joint-name value) pair of every named configuration of ROBOT."
  (loop for bindings in (cut:force-ll
                         (prolog:prolog `(rob-int:robot-joint-states ,robot ?_ ?_ ?_ ?states)))
        append (cut:var-value '?states bindings)))

(defun limit-violations (model robot)
  "The (joint value lower upper) entries of ROBOT's named configurations outside the URDF limits."
  (loop for (name value) in (joint-state-entries robot)
        for joint = (gethash name (urdf-model-joints model))
        when (and joint
                  (member (urdf-joint-type joint) '("revolute" "prismatic") :test #'string=)
                  (not (<= (- (urdf-joint-lower joint) 1d-9) value (+ (urdf-joint-upper joint) 1d-9))))
          collect (list name value (urdf-joint-lower joint) (urdf-joint-upper joint))))

(test pr2-names-exist-in-the-urdf
  (with-urdf (model "pr2")
    (let* ((joint-names (alexandria:hash-table-keys (urdf-model-joints model)))
           (links (named-links :pr2))
           (joints (named-joints :pr2))
           (missing-links (missing-names links (urdf-model-links model)))
           (missing-joints (missing-names joints joint-names)))
      (is (string-equal "pr2" (urdf-model-name model)))
      (is (eq :pr2 (rob-int:urdf-name->robot-name (urdf-model-name model))))
      (is (<= 20 (length links)))
      (is (<= 20 (length joints)))
      (is (null missing-links) "PR2 links missing from the URDF: ~s" missing-links)
      (is (null missing-joints) "PR2 joints missing from the URDF: ~s" missing-joints))))

(defparameter *pepper-names-absent-from-the-model*
  '("LThumb1" "RThumb1" "torse")
  "Names in the Pepper tutorial's facts that are no link of the Pepper model: the tool
frames are named after the thumb joints, and the torso link is spelt \"torse\".")

(test pepper-names-exist-in-the-urdf
  (with-urdf (model "pepper")
    (let* ((joint-names (alexandria:hash-table-keys (urdf-model-joints model)))
           (links (named-links *pepper*))
           (joints (named-joints *pepper*))
           (missing-links (missing-names links (urdf-model-links model)))
           (missing-joints (missing-names joints joint-names)))
      (is (eq *pepper* (with-robot (nil) (rob-int:set-robot-name (urdf-model-name model)))))
      (is (<= 15 (length links)))
      (is (<= 15 (length joints)))
      (is (subsetp missing-links *pepper-names-absent-from-the-model* :test #'string=)
          "Pepper links missing from the URDF: ~s" missing-links)
      (is (null missing-joints) "Pepper joints missing from the URDF: ~s" missing-joints)
      (is (every (lambda (name) (gethash name (urdf-model-joints model)))
                 (remove "torse" *pepper-names-absent-from-the-model* :test #'string=))
          "the thumb tool-frame names are joints of the model"))))

(test named-configurations-respect-the-urdf-limits
  (with-urdf (pr2 "pr2")
    (let ((violations (limit-violations pr2 :pr2))
          (entries (joint-state-entries :pr2)))
      (is (<= 14 (length entries)))
      (is (null violations) "PR2 configurations outside the limits: ~s" violations)))
  (with-urdf (pepper "pepper")
    (let ((violations (limit-violations pepper *pepper*))
          (entries (joint-state-entries *pepper*)))
      (is (<= 20 (length entries)))
      (is (null violations) "Pepper configurations outside the limits: ~s" violations))))

(test pr2-arm-joints-are-movable-and-follow-the-arm-links
  (with-urdf (model "pr2")
    (dolist (arm '(:left :right))
      (let* ((joints (rob-int:get-arm-joints :pr2 arm))
             (links (rob-int:get-arm-links :pr2 arm))
             (urdf-joints (mapcar (lambda (name) (gethash name (urdf-model-joints model))) joints))
             (children (mapcar (lambda (joint) (and joint (urdf-joint-child joint))) urdf-joints))
             (positions (mapcar (lambda (child) (position child links :test #'equal)) children))
             (end-effector (query-value '?l `(rob-int:end-effector-link :pr2 ,arm ?l))))
        (is (every #'identity urdf-joints))
        (is (notany (lambda (joint) (and joint (string= "fixed" (urdf-joint-type joint))))
                    urdf-joints))
        (is (every #'integerp positions) "every arm joint moves a link of ARM-LINKS: ~s" children)
        (is (equal positions (sort (copy-list positions) #'<)) "joints and links share one order")
        (is (equal (car (last children)) end-effector))))))

(defun fixed-offset (model from-link to-link)
  "The summed joint origins from FROM-LINK down to TO-LINK through joints without
rotation, as a list (x y z), or NIL when TO-LINK does not hang below FROM-LINK that way."
  (let ((by-child (make-hash-table :test 'equal)))
    (maphash (lambda (name joint) (declare (ignore name))
               (setf (gethash (urdf-joint-child joint) by-child) joint))
             (urdf-model-joints model))
    (loop with sum = (list 0d0 0d0 0d0)
          for link = to-link then (urdf-joint-parent joint)
          for joint = (gethash link by-child)
          until (equal link from-link)
          do (when (or (null joint) (notevery #'zerop (urdf-joint-rpy joint)))
               (return nil))
             (setf sum (mapcar #'+ sum (urdf-joint-xyz joint)))
          finally (return sum))))

(test pr2-tcp-in-ee-pose-matches-the-urdf
  (with-urdf (model "pr2")
    (dolist (arm '(:left :right))
      (let* ((ee (query-value '?l `(rob-int:end-effector-link :pr2 ,arm ?l)))
             (tool (query-value '?f `(rob-int:robot-tool-frame :pr2 ,arm ?f)))
             (tcp (query-value '?p '(rob-int:tcp-in-ee-pose :pr2 ?p)))
             (offset (fixed-offset model ee tool))
             (origin (cl-transforms:origin tcp)))
        (is (listp offset))
        (is (= 3 (length offset)) "the tool frame hangs below the end-effector link")
        (when (= 3 (length offset))
          (is (< (abs (- (first offset) (cl-transforms:x origin))) 1d-6))
          (is (< (abs (- (second offset) (cl-transforms:y origin))) 1d-6))
          (is (< (abs (- (third offset) (cl-transforms:z origin))) 1d-6)))))))

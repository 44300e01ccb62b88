;;;; Seed 003, the blocks in page order (helpers in seed-003.lisp).

(in-package :seeds)

(defmacro file-block (line (&key name (package "CRAM-PEPPER-DEMO")) pkg relpath &body checks)
  "The block at page LINE is a file the page has the user create: write it into the package PKG
as RELPATH, then run CHECKS (TEXT is the block's text)."
  `(equivalent-block (block-of-line ,line) (:name ,name :reason ,(format nil "the user's file ~a/~a" pkg relpath))
     (declare (ignorable text))
     (write-user-file ,pkg ,relpath text)
     (when (member (pathname-type ,relpath) '("lisp" "asd") :test #'equal)
       (expect (read-forms text ,package) "no forms in ~a" ,relpath))
     ,@checks))

(defmacro paste-block (line (&key name top completions) file &body checks)
  "The block at page LINE is code the page has the user paste into the demo's FILE (at its top
when TOP) and compile: the file is written and compiled (loaded), then CHECKS run."
  `(replay-block (block-of-line ,line) (:name ,name :package "CRAM-PEPPER-DEMO" :evaluate nil
                                        :completions ,completions)
     (add-chunks ,file (block-text (block-of-line ,line) :completions ,completions) :top ,top)
     (compile-user-file ,file)
     ,@checks))

(defun launch-text () (uiop:read-file-string (merge-pathnames "launch/pepper.launch" *checkout*)))

;;; ---- pepper_description (the models and upload.launch) ------------------------------------

(equivalent-block 1 (:name "pepper_description package.xml" :reason "catkin package of URDFs")
  (expect (search "<name>pepper_description</name>" text) "not the package.xml")
  (expect (and (probe-file (merge-pathnames "robots/pepper/pepper.urdf" *checkout*))
               (probe-file (merge-pathnames "resources/dm_shelves.urdf" *checkout*)))
          "cram-plans lacks the Pepper and shelf URDFs the package holds"))
(equivalent-block 2 (:name "CMakeLists find_package" :reason "catkin build step")
  (expect (search "robot_state_publisher" text) "not the CMake fragment")
  (expect (search "robot_state_publisher" (launch-text)) "pepper.launch runs no robot_state_publisher"))
(equivalent-block 3 (:name "comment out robot-current-pose generator" :reason "edit of CRAM's own file")
  (expect (search "robot-current-pose-tf-generator" text) "not the generator")
  ;; the location generators of cram-plans never answer a visibility designator with the pose the
  ;; robot stands at only because it stands there: checked in block 56 (generate-robot-pose)
  t)
(equivalent-block 4 (:name "map.launch" :reason "launch file fragment")
  (expect (search "map.launch" text) "not the map include")
  (expect (search "map_publisher.py" (launch-text)) "pepper.launch publishes no /map"))
(equivalent-block 5 (:name "descriptions" :reason "launch file fragment")
  (expect (search "shelf_description" text) "not the params")
  (expect (and (search "<param name=\"robot_description\"" (launch-text))
               (search "<param name=\"shelf_description\"" (launch-text)))
          "pepper.launch uploads neither description"))
(equivalent-block 6 (:name "joint state publishers" :reason "launch file fragment")
  (expect (search "shelf_state_publisher" (launch-text)) "pepper.launch lacks shelf_state_publisher"))
(equivalent-block 7 (:name "robot state publishers" :reason "launch file fragment")
  (expect (search "shelf_tf_state_publisher" (launch-text)) "pepper.launch lacks shelf_tf_state_publisher"))
(equivalent-block 8 (:name "static transforms" :reason "launch file fragment")
  (expect (and (search "pepper_wrt_map_tf" (launch-text)) (search "shelf_wrt_map_tf" (launch-text)))
          "pepper.launch lacks the map transforms"))
(equivalent-block 9 (:name "roslaunch upload.launch" :reason "shell: roslaunch launch/pepper.launch")
  (start-private-ros "launch/pepper.launch")
  (let ((params (ros-run "rosparam" "list")))
    (expect (and (search "/robot_description" params) (search "/shelf_description" params))
            "the parameters are not uploaded: ~a" params)))

;;; ---- cram_pepper_description ------------------------------------------------------------

(file-block 193 (:name "package.xml") "cram_pepper_description" "package.xml"
  (expect (string= "cram_pepper_description"
                   (ros-load-manifest::package-xml-name (pkg-file "cram_pepper_description" "package.xml")))
          "package.xml names another package"))
(file-block 214 (:name "CMakeLists.txt") "cram_pepper_description" "CMakeLists.txt")
(file-block 227 (:name "cram-pepper-description.asd") "cram_pepper_description" "cram-pepper-description.asd")
(file-block 249 (:name "package.lisp" :package "CL-USER") "cram_pepper_description" "src/package.lisp")
(file-block 262 (:name "neck.lisp" :package "PEPPER-DESCR") "cram_pepper_description" "src/neck.lisp")
(file-block 308 (:name "arms.lisp" :package "PEPPER-DESCR") "cram_pepper_description" "src/arms.lisp")
(file-block 421 (:name "general-knowledge.lisp" :package "PEPPER-DESCR")
    "cram_pepper_description" "src/general-knowledge.lisp")
(equivalent-block 17 (:name "roslaunch again" :reason "shell: the launch of block 9 still runs")
  (expect (search "/map_server" (ros-run "rosnode" "list")) "the launch is not running"))

(replay-block 18 (:name "load cram_pepper_description")
  (let ((system (asdf:find-system "cram-pepper-description")))
    (expect (and system (search *ws* (namestring (asdf:system-source-file system))))
            "loaded ~s, not the user's package" (and system (asdf:system-source-file system)))
    ;; the user's facts are the ones answering
    (expect (equal "base_link" (cut:var-value '?f (cut:lazy-car (prolog:prolog `(cram-robot-interfaces:robot-base-frame
                                                                              cram-pepper-description:pepper ?f)))))
            "the base frame fact is not the user's")))
(replay-block 19 (:name "in-package pepper-descr")
  (printed-like (first (result-values result)) (shown-output result)))

;;; ---- cram_pepper_demo -------------------------------------------------------------------

(file-block 516 (:name "package.xml") "cram_pepper_demo" "package.xml")
(file-block 575 (:name "CMakeLists.txt") "cram_pepper_demo" "CMakeLists.txt")
(file-block 586 (:name "cram-pepper-demo.asd") "cram_pepper_demo" "cram-pepper-demo.asd")
(file-block 648 (:name "package.lisp" :package "CL-USER") "cram_pepper_demo" "src/package.lisp")
(equivalent-block 24 (:name "(in-package :demo) atop the other files" :reason "editor step")
  (dolist (file '("setup.lisp" "projection-demo.lisp" "cram-plans.lisp" "shelf-prolog.lisp"))
    (setf (gethash file *chunks*) (list (cons '(in-package) (string-trim " " text))))
    (add-chunks file "")
    (expect (probe-file (pkg-file "cram_pepper_demo" (format nil "src/~a" file))) "no ~a" file))
  ;; the product meshes of the page's resource folder: the project's own meshes
  (dolist (mesh (directory (merge-pathnames "resources/meshes/*.stl" *checkout*)))
    (let ((to (pkg-file "cram_pepper_demo" (format nil "resource/~a.stl" (pathname-name mesh)))))
      (ensure-directories-exist to)
      (uiop:copy-file mesh to))))
(replay-block 25 (:name "load cram_pepper_demo")
  (let ((system (asdf:find-system "cram-pepper-demo")))
    (expect (and system (search *ws* (namestring (asdf:system-source-file system))))
            "loaded ~s, not the user's package" (and system (asdf:system-source-file system)))))
(replay-block 26 (:name "in-package demo")
  (printed-like (first (result-values result)) (shown-output result)))

(file-block 677 (:name "setup.lisp") "cram_pepper_demo" "src/setup.lisp"
  (setf (gethash "setup.lisp" *chunks*) (list (cons '(file) text))))
(defun setup-file-text () (uiop:read-file-string (pkg-file "cram_pepper_demo" "src/setup.lisp")))
(dolist (line '(747 753 797 822))
  (replay-block (block-of-line line) (:name "setup.lisp explained" :package "CRAM-PEPPER-DEMO")
    (expect (same-forms-p (block-text (block-of-line line)) (setup-file-text) :demo)
            "the explained code differs from setup.lisp")))

(defun prose-step (what thunk)
  "A step the page's prose asks for between code blocks (no code block of its own)."
  (format t "~&;; seed 003 prose step: ~a~%" what)
  (handler-case (funcall thunk)
    (error (e) (format t "~&;; seed 003 prose step failed: ~a~%" e))))

(defun reload-demo ()
  (ros-load:load-system "cram_pepper_demo" :cram-pepper-demo))

(defun first-answer-like (value shown)
  "The first answer of the lazy list VALUE prints as the page's SHOWN answer."
  (printed-like (list (cut:lazy-car value)) (subseq shown 0 (1+ (or (search "))" shown) (- (length shown) 2))))))

(prose-step "compile the project, load the cram_pepper_demo package" #'reload-demo)
(replay-block 32 (:name "startup-ros" :package "CRAM-PEPPER-DEMO")
  (expect (and (obj :floor) (obj :kitchen) (pepper)) "the world lacks floor, shelves or Pepper: ~a"
          (mapcar #'btr:name (btr:objects (world))))
  (expect (string-equal "pepper" (string (btr:name (pepper)))) "the robot is ~a" (btr:name (pepper)))
  (expect (< (abs (third (xyz (btr:link-pose (pepper) "base_footprint")))) 0.01)
          "Pepper does not stand on the floor: base_footprint at ~a" (xyz (btr:link-pose (pepper) "base_footprint")))
  (expect (find :|KITCHEN.shelf_1_level_4_link| (shelf-names)) "the shelves have no level links"))
(replay-block 33 (:name "the world")
  (printed-like (first (result-values result)) (shown-output result)))
(replay-block 34 (:name "move Pepper 2 m forward" :package "CRAM-PEPPER-DEMO")
  (first-answer-like (first (result-values result)) (shown-output result))
  (expect (near (xyz (btr:pose (pepper))) '(2 0 0) 1d-6) "Pepper at ~a" (xyz (btr:pose (pepper)))))
(replay-block 35 (:name "a box of cereal" :package "CRAM-PEPPER-DEMO")
  (let ((c (obj :my-cereal1)))
    (expect (and c (near (xyz (btr:pose c)) '(4.1 0 1.03) 1d-6)) "cereal at ~a" (and c (xyz (btr:pose c))))
    (expect (> (first (xyz (btr:pose c))) (first (xyz (btr:pose (pepper))))) "the cereal is not in front of Pepper")))

(paste-block 875 (:name "spawn-products-one") "cram-plans.lisp")
(prose-step "restart, load the package and load up the scene" (lambda () (reload-demo) (call 'init-projection)))
(defparameter *products*
  '((:my-cereal1 (4.1 0 1.03)) (:my-cereal2 (2 -1.4 1.05)) (:my-cereal3 (4.1 0.15 1.73))
    (:my-sachet1 (4.1 -0.55 1.03)) (:my-sachet2 (4.1 0.15 1.4)) (:my-sachet3 (4.1 -0.3 1.73))
    (:my-milk1 (4.1 -0.55 1.4)) (:my-milk2 (1.5 -1.4 1.37)) (:my-bowl1 (1.5 -1.4 0.52))
    (:my-bowl2 (1.8 -1.4 0.52)) (:my-bar1 (1.5 -1.4 0.77)) (:my-bar2 (1.8 -1.4 0.77))))
(replay-block 37 (:name "spawn the products" :package "CRAM-PEPPER-DEMO")
  (loop for (name at) in *products*
        do (expect (and (obj name) (near (xyz (btr:pose (obj name))) at 1d-6))
                   "~a is not at ~a" name at)))

(paste-block 931 (:name "park-arms") "cram-plans.lisp")
(replay-block 39 (:name "park the arms" :package "CRAM-PEPPER-DEMO")
  (expect (and (joints-at (symbol-value (find-symbol "*LEFT-PARKING-JOINT-STATES*" :pepper-descr)) 0.01)
               (joints-at (symbol-value (find-symbol "*RIGHT-PARKING-JOINT-STATES*" :pepper-descr)) 0.01))
          "the arms are not parked"))
(paste-block 952 (:name "spawn-human") "cram-plans.lisp")
(replay-block 41 (:name "spawn the human" :package "CRAM-PEPPER-DEMO")
  (first-answer-like (first (result-values result)) (shown-output result))
  (let ((h (obj :my-human)))
    (expect (and h (near (xyz (btr:pose h)) '(-1 0 1) 1d-6)) "the human is not at (-1 0 1)")
    (expect (< (first (xyz (btr:pose h))) (first (xyz (btr:pose (pepper))))) "the human is not behind Pepper")))
(paste-block 974 (:name "reposition-robot") "cram-plans.lisp")
(replay-block 43 (:name "face the human" :package "CRAM-PEPPER-DEMO")
  (first-answer-like (first (result-values result)) (shown-output result))
  (expect (and (near (xyz (btr:pose (pepper))) '(0 0 0) 1d-6) (> (abs (yaw (btr:pose (pepper)))) 3.14))
          "Pepper does not face the human: ~a yaw ~a" (xyz (btr:pose (pepper))) (yaw (btr:pose (pepper)))))

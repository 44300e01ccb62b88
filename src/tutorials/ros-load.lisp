;;;; ROS-LOAD:LOAD-SYSTEM as the tutorials call it, (ros-load:load-system "cram_pepper_demo"
;;;; :cram-pepper-demo), mapped to this project's ASDF systems. The package is the one roslisp
;;;; names ROS-LOAD-MANIFEST (nickname ROS-LOAD), so that loading Debian's roslisp later finds it
;;;; and extends it instead of clashing with it.
;;;;
;;;; A user's own ROS package wins: a package on ROS_PACKAGE_PATH (crawled as rospack does)
;;;; that holds the system's .asd file is loaded from there, even when this project has a
;;;; built-in package of the same name (the tutorials' cram_pepper_description and
;;;; cram_pepper_demo). The CRAM system names such .asd files depend on (cram-prolog, cram-tf,
;;;; cl-tf2, cram-bullet-reasoning-belief-state ...) resolve to the systems of this project that
;;;; provide them (CRAM-SYSTEM-ALIAS).

(eval-when (:compile-toplevel :load-toplevel :execute)
  (unless (find-package :ros-load-manifest)
    (make-package :ros-load-manifest :nicknames '(:ros-load) :use '(:cl))
    (export (mapcar (lambda (name) (intern name :ros-load-manifest))
                    '("LOAD-SYSTEM" "*CURRENT-ROS-PACKAGE*"))
            :ros-load-manifest)))

(in-package :ros-load-manifest)

(defvar *current-ros-package* nil
  "The ROS package whose system LOAD-SYSTEM is loading.")

(defun ros-package-system-name (ros-package)
  "The ASDF system name for the ROS package ROS-PACKAGE (underscores read as hyphens); this
project provides it as cram-plans/NAME."
  (unless (and (stringp ros-package) (plusp (length ros-package)))
    (error "ROS-LOAD: expected a ROS package name string such as \"cram_pepper_demo\", got ~s."
           ros-package))
  (substitute #\- #\_ (string-downcase ros-package)))

;;; ------------------------------------------------------------------------------------------
;;; ROS packages on ROS_PACKAGE_PATH

(defparameter *package-crawl-depth* 5
  "How many directory levels below each ROS_PACKAGE_PATH entry are searched for packages, and
below a package directory for its .asd files.")

(defvar *package-index* nil
  "The crawl of ROS_PACKAGE_PATH: (path-string . entries), each entry (name directory asd-files)
in the order rospack finds them.")

(defun package-xml-name (file)
  "The <name> of the package.xml FILE, or NIL."
  (let* ((text (ignore-errors (uiop:read-file-string file)))
         (start (and text (search "<name>" text)))
         (end (and start (search "</name>" text :start2 start))))
    (and end (string-trim '(#\Space #\Tab #\Newline #\Return) (subseq text (+ start 6) end)))))

(defun hidden-directory-p (dir)
  (let ((name (car (last (pathname-directory dir)))))
    (and (stringp name) (plusp (length name)) (char= (char name 0) #\.))))

(defun asd-files-below (dir depth)
  "The .asd files in DIR and its subdirectories down to DEPTH levels."
  (append (uiop:directory-files dir "*.asd")
          (when (plusp depth)
            (loop for sub in (uiop:subdirectories dir)
                  unless (hidden-directory-p sub)
                    append (asd-files-below sub (1- depth))))))

(defun crawl-packages (root depth)
  "The ROS packages in ROOT and below (a directory with a package.xml is a package; its
subdirectories are not searched for more), as (name directory asd-files)."
  (let ((xml (probe-file (merge-pathnames "package.xml" root))))
    (cond (xml (let ((name (package-xml-name xml)))
                 (and name (list (list name root (asd-files-below root *package-crawl-depth*))))))
          ((plusp depth)
           (loop for sub in (ignore-errors (uiop:subdirectories root))
                 unless (hidden-directory-p sub)
                   append (crawl-packages sub (1- depth)))))))

(defun ros-package-path-entries ()
  (remove-if (lambda (s) (zerop (length s)))
             (uiop:split-string (or (uiop:getenv "ROS_PACKAGE_PATH") "") :separator ":")))

(defun package-index (&key refresh)
  "The ROS packages on ROS_PACKAGE_PATH, crawled again when REFRESH or when the variable changed."
  (let ((path (or (uiop:getenv "ROS_PACKAGE_PATH") "")))
    (when (or refresh (null *package-index*) (string/= path (car *package-index*)))
      (setf *package-index*
            (cons path (loop for entry in (ros-package-path-entries)
                             for dir = (uiop:directory-exists-p (uiop:ensure-directory-pathname entry))
                             when dir append (crawl-packages dir *package-crawl-depth*)))))
    (cdr *package-index*)))

(defun user-system-file (system &key ros-package refresh)
  "The .asd file of the ASDF system SYSTEM (a lower-case string) in a ROS package on
ROS_PACKAGE_PATH: in ROS-PACKAGE when given, else in any package; the first one in path order."
  (loop for (name nil files) in (package-index :refresh refresh)
        when (or (null ros-package) (string= name ros-package))
          do (let ((file (find system files :key #'pathname-name :test #'string-equal)))
               (when file (return file)))))

(defun ros-package-directory (name)
  "The directory of the ROS package NAME found on ROS_PACKAGE_PATH (crawled as rospack does;
again when it is not found in the last crawl), or NIL."
  (flet ((lookup (refresh)
           (second (find name (package-index :refresh refresh) :key #'first :test #'string=))))
    (or (lookup nil) (lookup t))))

;;; ------------------------------------------------------------------------------------------
;;; CRAM's system names

(defparameter *cram-system-aliases*
  '(("cl-transforms-stamped" . "cram-plans/cl-transforms")
    ("cl-tf" . "cram-plans/cl-transforms")
    ("cl-tf2" . "cram-plans/cl-transforms")
    ("cram-tf" . "cram-plans/cl-transforms")
    ("cram-projection" . "cram-plans/cram-executive")
    ("cram-occasions-events" . "cram-plans/cram-executive")
    ("cram-plan-occasions-events" . "cram-plans/cram-executive")
    ("cram-process-modules" . "cram-plans/cram-executive")
    ("cram-physics-utils" . "cram-plans/cram-bullet-reasoning")
    ("cl-bullet" . "cram-plans/cram-bullet-reasoning")
    ("cl-urdf" . "cram-plans/cram-bullet-reasoning")
    ("cram-bullet-reasoning-belief-state" . "cram-plans/cram-bullet-reasoning")
    ("cram-bullet-reasoning-utilities" . "cram-plans/cram-bullet-reasoning")
    ("cram-btr-visibility-costmap" . "cram-plans/cram-location-costmap")
    ("cram-btr-spatial-relations-costmap" . "cram-plans/cram-location-costmap")
    ("cram-robot-pose-gaussian-costmap" . "cram-plans/cram-location-costmap")
    ("cram-occupancy-grid-costmap" . "cram-plans/cram-location-costmap")
    ("cram-manipulation-interfaces" . "cram-plans/cram-object-knowledge")
    ;; this project folds fetching and delivering into its pick and place plans
    ("cram-fetch-deliver-plans" . "cram-plans/cram-mobile-pick-place-plans")
    ;; CRAM's roslisp-utilities is built on roslisp
    ("roslisp-utilities" . "cram-plans/roslisp-utilities/ros"))
  "CRAM system names whose content this project provides in a system of another name.")

(defun cram-system-alias (name)
  "The system of this project that provides the CRAM system NAME (a string, e.g. \"cram-tf\" or
\"cram-prolog\"), or NIL."
  (let ((name (string-downcase name)))
    (or (cdr (assoc name *cram-system-aliases* :test #'string=))
        (let ((own (concatenate 'string "cram-plans/" name)))
          ;; registered systems only: looking up a missing secondary system of cram-plans.asd
          ;; makes ASDF read that file again, which redefines (and so reloads) every system
          (and (not (find #\/ name))
               (asdf:registered-system own)
               own)))))

(defun alias-directory ()
  (uiop:ensure-directory-pathname
   (merge-pathnames "cram-plans/system-aliases/" (uiop:xdg-cache-home))))

(defun alias-system-file (name target)
  "A .asd file defining the system NAME as this project's system TARGET (written once)."
  (let ((file (merge-pathnames (make-pathname :name name :type "asd") (alias-directory)))
        (text (format nil ";; The CRAM system ~a, provided by cram-plans as ~a.~%~
                           (asdf:defsystem ~s :depends-on (~s))~%" name target name target)))
    (unless (and (probe-file file) (string= text (uiop:read-file-string file)))
      (ensure-directories-exist file)
      (with-open-file (out file :direction :output :if-exists :supersede)
        (write-string text out)))
    file))

(defun cram-plans-system-search (name)
  "ASDF search function: the .asd of NAME in a ROS package on ROS_PACKAGE_PATH (the user's
packages win), else an alias of the system of this project that provides the CRAM system NAME."
  (let ((name (string-downcase (asdf:primary-system-name name))))
    (unless (or (string= name "cram-plans") (uiop:string-prefix-p "cram-plans/" name))
      (or (user-system-file name)
          (let ((target (cram-system-alias name)))
            (and target (alias-system-file name target)))))))

(unless (member 'cram-plans-system-search asdf:*system-definition-search-functions*)
  (setf asdf:*system-definition-search-functions*
        (append asdf:*system-definition-search-functions* (list 'cram-plans-system-search))))

;;; ------------------------------------------------------------------------------------------
;;; LOAD-SYSTEM

(defvar *roslisp-load-system* nil
  "roslisp's own LOAD-SYSTEM (it finds packages with rospack), kept for the ROS packages this
project does not provide; NIL when roslisp's loader is not loaded.")

(defun system-name-string (system default)
  (cond ((null system) default)
        ((symbolp system) (string-downcase (symbol-name system)))
        ((stringp system) (string-downcase system))
        (t (error "ROS-LOAD:LOAD-SYSTEM: expected a system name (symbol or string), got ~s." system))))

(defun cram-plans-load-system (ros-package &optional system force)
  "Load the ASDF SYSTEM (a symbol or string) of the ROS package ROS-PACKAGE; without SYSTEM
the one ROS-PACKAGE maps to. FORCE recompiles. Returns the system's name. The user's own
package on ROS_PACKAGE_PATH holding SYSTEM.asd wins (ROS_PACKAGE_PATH is crawled again on
every call); else this project's built-in system; a package this project does not provide is
handed to roslisp's loader when it is loaded."
  (let* ((default (ros-package-system-name ros-package))
         (name (system-name-string system default))
         (user (user-system-file name :ros-package ros-package :refresh t))
         ;; no current ROS package, so that roslisp's search (rospack) stays out
         (*current-ros-package* nil))
    (cond (user
           (let ((previous (asdf:find-system name nil)))
             ;; a system of that name defined elsewhere (another checkout of the package) is
             ;; replaced by the one of the package found on ROS_PACKAGE_PATH
             (when (and previous (not (equal (asdf:system-source-file previous) (truename user))))
               (asdf:clear-system name)))
           (asdf:load-asd user)
           (asdf:load-system name :force force)
           name)
          (t
           (let ((found (find-if (lambda (n) (asdf:find-system n nil))
                                 (list (concatenate 'string "cram-plans/" name) name))))
             (cond (found
                    (asdf:load-system found :force force)
                    found)
                   (*roslisp-load-system*
                    (funcall *roslisp-load-system* ros-package (or system ros-package) force))
                   (t
                    (error "ROS-LOAD:LOAD-SYSTEM: no ASDF system ~s for the ROS package ~s (not ~
                            on ROS_PACKAGE_PATH as ~a.asd, nor one of this project's)."
                           name ros-package name))))))))

(defun install-cram-plans-load-system ()
  "Make ROS-LOAD:LOAD-SYSTEM this project's loader, keeping roslisp's when it was defined (roslisp
defines the same function when it loads: STARTUP-ROS calls this again after loading roslisp)."
  (let ((current (and (fboundp 'load-system) (fdefinition 'load-system))))
    (unless (and current
                 (eq (nth-value 2 (function-lambda-expression current)) 'cram-plans-load-system))
      (when current (setf *roslisp-load-system* current))
      (setf (fdefinition 'load-system) #'cram-plans-load-system
            (documentation 'load-system 'function) (documentation 'cram-plans-load-system 'function))))
  'load-system)

(install-cram-plans-load-system)

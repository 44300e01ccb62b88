;;;; Package of the ROS integration: node start and stop with init and cleanup functions, the
;;;; master's reachability, URDFs from the parameter server, and the belief state on /tf and
;;;; /visualization_marker_array.

(defpackage :roslisp-utilities
  (:use :cl)
  (:export
   ;; ROS_HOME
   #:ros-home-directory #:ensure-ros-home
   ;; the master
   #:ros-master-uri #:ros-available-p #:ros-master-unreachable #:free-local-port
   #:ros-master-unreachable-uri #:ros-master-unreachable-source
   #:ros-utilities-error
   ;; node life cycle
   #:startup-ros #:shutdown-ros #:ros-running-p #:ros-log
   #:register-ros-init-function #:register-ros-cleanup-function
   #:unregister-ros-init-function #:unregister-ros-cleanup-function
   #:ros-init-functions #:ros-cleanup-functions
   ;; which world startup-ros builds
   #:register-ros-world #:ros-worlds #:select-init-functions #:ros-world-error
   #:*ros-init-functions* #:*ros-cleanup-functions* #:make-function-registry
   ;; URDFs from the parameter server
   #:robot-description-string #:description-parameter-missing
   ;; names
   #:rosify-underscores-lisp-name #:rosify-lisp-name #:lispify-ros-underscore-name
   #:lispify-ros-name
   ;; the belief state on /tf and markers
   #:*belief-state-publish-rate* #:*tf-fixed-frame* #:*environment-tf-prefix*
   #:*tf-topic* #:*marker-topic* #:*marker-namespace* #:*marker-mesh-uris*
   #:object-frame-name #:belief-state-transforms #:belief-state-markers
   #:publish-belief-state #:start-belief-state-publisher #:stop-belief-state-publisher
   #:belief-state-publisher-running-p))
